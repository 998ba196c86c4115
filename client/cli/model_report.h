#pragma once

// `geodex info`'s report for a person: the layout of `geodex-query --info`
// (core/index/index_report.h), drawn from the report's JSON the server sends
// (ModelInfo.report_json). The client depends on the proto only, so it lays
// the figures out itself; the figures and the sentences are the server's.

#include <string>

#include "absl/status/statusor.h"
#include "geodex/client/types.h"

namespace geodex::client::cli {

// The report of `model`, headed by its name, version and state. A model the
// server sends no report JSON for (not serving, or an older server) gets its
// counts and its build report's "key = value" lines. Errors: InvalidArgument
// when report_json is not a JSON object of the documented shape.
absl::StatusOr<std::string> ModelReportText(const ModelInfo& model);

// `fraction` as a percentage with three significant digits and no exponent,
// as the core's report and the viewer write it ("1.31%", "0.00780%", "643%",
// "<0.001%", "0%").
std::string FormatPercent(double fraction);

}  // namespace geodex::client::cli
