#pragma once

// The Markdown tables the benchmarks print (and the pages of tests/bench quote).

#include <string>
#include <string_view>
#include <vector>

namespace geodex::bench {

// "| a | b | c |": one table row, without a newline.
std::string MarkdownRow(const std::vector<std::string>& cells);

// The header row of `titles` and the rule below it, each ending in a
// newline. `right_aligned` holds one character per column, 'r' for a column
// aligned right ("---:"); shorter or empty: the other columns are plain
// ("---").
std::string MarkdownHeader(const std::vector<std::string>& titles,
                           std::string_view right_aligned = "");

}  // namespace geodex::bench
