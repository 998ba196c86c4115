#include "tests/bench/bench_table.h"

namespace geodex::bench {

std::string MarkdownRow(const std::vector<std::string>& cells) {
  std::string row = "|";
  for (const std::string& cell : cells) row += " " + cell + " |";
  return row;
}

std::string MarkdownHeader(const std::vector<std::string>& titles, std::string_view right_aligned) {
  std::string rule = "|";
  for (size_t i = 0; i < titles.size(); ++i) {
    rule += i < right_aligned.size() && right_aligned[i] == 'r' ? "---:|" : "---|";
  }
  return MarkdownRow(titles) + "\n" + rule + "\n";
}

}  // namespace geodex::bench
