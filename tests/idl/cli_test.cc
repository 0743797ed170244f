// Tests cli.h: numbers are read whole and in range or refused with a message naming the flag,
// the range and the text given; numbers are written as people write them; the option loop hands
// every argument over in order, with its value, and refuses what the tool does not take.
#include "telegrasp/idl/cli.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace telegrasp::cli {
namespace {

// A usage error that returns to the test instead of exiting.
struct Refused {
  std::string what;
};
void refuse(const std::string& what) { throw Refused{what}; }

template <class F>
std::string refusal(F&& f) {
  try {
    f();
  } catch (const Refused& r) {
    return r.what;
  }
  return "";
}

TEST(CliTest, FormatsNumbersAsPeopleWriteThem) {
  EXPECT_EQ(format_number(0.0), "0");
  EXPECT_EQ(format_number(0.25), "0.25");
  EXPECT_EQ(format_number(90.0), "90");
  EXPECT_EQ(format_number(-1.5), "-1.5");
  EXPECT_EQ(format_number(0.1), "0.1");
  EXPECT_EQ(format_number(1e9), "1000000000");
  EXPECT_EQ(format_number(-0.0), "0");
  EXPECT_EQ(std::stod(format_number(1.0 / 3.0)), 1.0 / 3.0);  // shortest text that reads back
}

TEST(CliTest, ReadsWholeNumbersInRangeAndNamesTheMistake) {
  EXPECT_EQ(parse_whole("--trials", "12", 1, 100, refuse), 12);
  for (const char* bad : {"", "1.5", "7x", " 7", "99999999999999999999999"})
    EXPECT_NE(refusal([&] { (void)parse_whole("--n", bad, 0, 100, refuse); }), "") << "'" << bad << "'";
}

TEST(CliTest, ReadsFiniteNumbersInRangeAndNamesTheMistake) {
  EXPECT_EQ(parse_number("--seconds", "0.5", 0.1, 86400, refuse), 0.5);
  EXPECT_EQ(refusal([] { (void)parse_number("--timeout", "0", 0.1, 86400, refuse); }),
            "--timeout expects a number in [0.1, 86400], got '0'");
  for (const char* bad : {"", "nan", "inf", "1e400", "3s"})
    EXPECT_NE(refusal([&] { (void)parse_number("--x", bad, -1e9, 1e9, refuse); }), "") << "'" << bad << "'";
}

// argv as the option loop gets it: a program name, then the arguments.
struct Argv {
  explicit Argv(std::vector<std::string> args) : strings(std::move(args)) {
    strings.insert(strings.begin(), "tool");
    for (std::string& s : strings) pointers.push_back(s.data());
  }
  int argc() const { return static_cast<int>(pointers.size()); }
  std::vector<std::string> strings;
  std::vector<char*> pointers;
};

TEST(CliTest, OptionLoopHandsOverEachArgumentInOrderWithItsValue) {
  Argv a({"--name", "x", "FILE", "--flag", "--tag", "1", "--tag", "2"});
  std::vector<std::string> seen;
  for_each_option(a.argc(), a.pointers.data(), "usage", refuse, [&](const std::string& arg, const auto& value) {
    if (arg == "--name" || arg == "--tag")
      seen.push_back(arg + "=" + value());
    else if (arg == "--flag" || !is_option(arg))
      seen.push_back(arg);
    else
      return false;
    return true;
  });
  EXPECT_EQ(seen, (std::vector<std::string>{"--name=x", "FILE", "--flag", "--tag=1", "--tag=2"}));
}

TEST(CliTest, OptionLoopRefusesUnknownOptionsStrayArgumentsAndMissingValues) {
  auto parse = [](std::vector<std::string> args) {
    return refusal([&] {
      Argv a(std::move(args));
      for_each_option(a.argc(), a.pointers.data(), "usage", refuse, [](const std::string& arg, const auto& value) {
        if (arg == "--name") return !value().empty();
        return false;
      });
    });
  };
  EXPECT_EQ(parse({"--bogus"}), "unknown option '--bogus'");
  EXPECT_EQ(parse({"stray"}), "unexpected argument 'stray'");
  EXPECT_EQ(parse({"--name"}), "--name needs a value");
  EXPECT_EQ(parse({"--name", "x"}), "");
}

// A renamed flag: the new name is taken silently, the old one is taken with a warning naming
// both, anything else is not this flag.
TEST(CliTest, ARenamedFlagTakesBothSpellingsAndWarnsOnTheOldOne) {
  ::testing::internal::CaptureStderr();
  EXPECT_TRUE(is_flag("tool", "--timeout-s", "--timeout-s", "--timeout"));
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  ::testing::internal::CaptureStderr();
  EXPECT_TRUE(is_flag("tool", "--timeout", "--timeout-s", "--timeout"));
  EXPECT_EQ(::testing::internal::GetCapturedStderr(),
            "tool: deprecated: --timeout is now --timeout-s (--timeout goes in the next release)\n");
  ::testing::internal::CaptureStderr();
  EXPECT_FALSE(is_flag("tool", "--timeouts", "--timeout-s", "--timeout"));
  EXPECT_FALSE(is_flag("tool", "--trials", "--timeout-s", "--timeout"));
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}


// A table of text options: the matching one gets its value, in the order given; others are left.
TEST(CliTest, TextFlagsStoreTheirValueWhereTheTableSays) {
  std::string json, report;
  const std::vector<std::string> values = {"out.json", "r.html"};
  std::size_t taken = 0;
  auto value = [&] { return values.at(taken++); };
  EXPECT_TRUE(text_flag("--json", value, {{"--json", &json}, {"--report", &report}}));
  EXPECT_TRUE(text_flag("--report", value, {{"--json", &json}, {"--report", &report}}));
  EXPECT_FALSE(text_flag("--csv", value, {{"--json", &json}, {"--report", &report}}));
  EXPECT_EQ(json, "out.json");
  EXPECT_EQ(report, "r.html");
  EXPECT_EQ(taken, 2u);  // --csv took no value
}

}  // namespace
}  // namespace telegrasp::cli
