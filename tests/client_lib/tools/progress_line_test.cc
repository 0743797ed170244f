// Tests ProgressLine: on a terminal one line is rewritten in place; in a log a plain line is
// written at most once per period, and the last line always.
#include "progress_line.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace telegrasp::tools {
namespace {

using namespace std::chrono_literals;

// What `out` holds.
std::string contents(std::FILE* out) {
  std::fflush(out);
  std::rewind(out);
  std::string text;
  for (int c; (c = std::fgetc(out)) != EOF;) text += static_cast<char>(c);
  return text;
}

// A clock the test moves by hand.
struct FakeClock {
  ProgressLine::Clock::time_point t{};
  ProgressLine::Clock::time_point operator()() const { return t; }
};

// A temporary file for the line, closed after the test, and a clock the test moves.
class ProgressLineTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_NE(out, nullptr); }
  void TearDown() override {
    if (out != nullptr) std::fclose(out);
  }
  // The clock for a ProgressLine: reads `clock`.
  auto fake_clock() {
    return [this] { return clock(); };
  }

  std::FILE* out = std::tmpfile();
  FakeClock clock;
};

TEST_F(ProgressLineTest, LogGetsALineAtMostEveryPeriodAndTheLastOne) {
  ProgressLine progress(out, false, 200ms, 5s, fake_clock());
  progress.show("1/4");  // the first is written
  clock.t += 1s;
  EXPECT_FALSE(progress.due());
  progress.show("2/4");  // 1 s later: not yet
  clock.t += 4s;
  progress.show("3/4");  // 5 s after the first: written
  progress.finish("4/4");
  EXPECT_EQ(contents(out), "1/4\n3/4\n4/4\n");
}

TEST_F(ProgressLineTest, LogDoesNotRepeatALastLineItAlreadyHolds) {
  ProgressLine progress(out, false, 200ms, 5s);
  progress.show("done");
  progress.finish("done");
  EXPECT_EQ(contents(out), "done\n");
}

TEST_F(ProgressLineTest, TerminalRewritesOneLineAndEndsItAtTheFinish) {
  ProgressLine progress(out, true, 200ms, 5s, fake_clock());
  progress.show("1/10 long");
  clock.t += 300ms;
  progress.show("2/10");  // padded over the longer line before it
  progress.break_line();  // a message of its own may follow
  progress.break_line();  // only one line end
  progress.finish("10/10");
  EXPECT_EQ(contents(out), "\r1/10 long\r2/10     \n\r10/10\n");
}

}  // namespace
}  // namespace telegrasp::tools
