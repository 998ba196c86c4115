#include "core/builder/build_progress.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "gtest/gtest.h"

namespace geodex::builder {
namespace {

// The "elapsed" figures of the printer's log lines, in order.
std::vector<double> ElapsedSeconds(std::FILE* file) {
  std::rewind(file);
  std::vector<double> out;
  char line[256];
  while (std::fgets(line, sizeof(line), file) != nullptr) {
    const char* at = std::strstr(line, "elapsed ");
    if (at == nullptr) continue;
    int minutes = 0;
    double seconds = 0;
    if (std::sscanf(at, "elapsed %dm%lfs", &minutes, &seconds) == 2) {
      out.push_back(60 * minutes + seconds);
    } else if (std::sscanf(at, "elapsed %lfs", &seconds) == 1) {
      out.push_back(seconds);
    }
  }
  return out;
}

// A target-error build runs sampling, repair and rows once a round: the
// clock of every line is the build's, so it never runs backwards when a
// phase begins again or another begins.
TEST(ProgressPrinterTest, ElapsedIsTheBuildsClockAndNeverRunsBackwards) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  ProgressPrinter printer(file);  // not a terminal: a line at each phase's end
  const auto pause = [] { std::this_thread::sleep_for(std::chrono::milliseconds(150)); };
  for (int round = 0; round < 2; ++round) {
    printer({"sampling", 0, 10});
    pause();
    printer({"sampling", 10, 10});
    printer({"repair", 0, 1});
    pause();
    printer({"repair", 1, 1});
    printer({"rows", 10, 10});
  }
  const std::vector<double> elapsed = ElapsedSeconds(file);
  std::fclose(file);
  // Each phase's end, and the first call's line.
  ASSERT_EQ(elapsed.size(), 7u);
  for (size_t i = 1; i < elapsed.size(); ++i) {
    EXPECT_GE(elapsed[i], elapsed[i - 1]) << "line " << i;
  }
  // Four pauses of 0.15 s: the last line is the whole build's time.
  EXPECT_GE(elapsed.back(), 0.5);
}

TEST(ProgressPrinterTest, FormatsSecondsAndMinutes) {
  EXPECT_EQ(FormatSeconds(12.34), "12.3s");
  EXPECT_EQ(FormatSeconds(125), "2m05s");
}

}  // namespace
}  // namespace geodex::builder
