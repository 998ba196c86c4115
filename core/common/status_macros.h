#pragma once

// Small helpers for absl::Status plumbing; Abseil 20220623 ships none.

#include "absl/status/status.h"
#include "absl/status/statusor.h"

#define GEODEX_STATUS_CONCAT_INNER_(a, b) a##b
#define GEODEX_STATUS_CONCAT_(a, b) GEODEX_STATUS_CONCAT_INNER_(a, b)

// GEODEX_RETURN_IF_ERROR(expr): evaluates `expr` (an absl::Status) and returns
// it from the enclosing function if it is not OK.
#define GEODEX_RETURN_IF_ERROR(expr)                 \
  do {                                               \
    ::absl::Status geodex_status_ = (expr);          \
    if (!geodex_status_.ok()) return geodex_status_; \
  } while (false)

// GEODEX_ASSIGN_OR_RETURN(lhs, expr): evaluates `expr` (an absl::StatusOr<T>);
// on error returns its status, otherwise moves the value into `lhs`, which may
// be a declaration (`auto mesh`).
#define GEODEX_ASSIGN_OR_RETURN(lhs, expr) \
  GEODEX_ASSIGN_OR_RETURN_IMPL_(GEODEX_STATUS_CONCAT_(geodex_statusor_, __LINE__), lhs, expr)
#define GEODEX_ASSIGN_OR_RETURN_IMPL_(tmp, lhs, expr) \
  auto tmp = (expr);                                  \
  if (!tmp.ok()) return std::move(tmp).status();      \
  lhs = std::move(tmp).value()
