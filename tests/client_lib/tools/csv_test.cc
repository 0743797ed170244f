// Tests csv.h: a field is quoted only when it must be (comma, double quote, CR, LF), and a
// double quote inside is doubled; reading the quoted text back by RFC 4180 gives the original.
#include "csv.h"

#include <gtest/gtest.h>

#include <string>

namespace telegrasp::csv {
namespace {

// The RFC 4180 reading of one quoted field: strip the outer quotes, undouble the inner ones.
std::string unquote(const std::string& quoted) {
  std::string out;
  for (std::size_t i = 1; i + 1 < quoted.size(); ++i) {
    out += quoted[i];
    if (quoted[i] == '"') ++i;  // the second quote of a doubled pair
  }
  return out;
}

TEST(CsvFieldTest, PlainFieldIsUnchanged) {
  EXPECT_EQ(field("014_lemon"), "014_lemon");
  EXPECT_EQ(field("072-a_toy_airplane"), "072-a_toy_airplane");
  EXPECT_EQ(field(""), "");
  EXPECT_EQ(field("two words; a tab\there"), "two words; a tab\there");
}

TEST(CsvFieldTest, CommaIsQuoted) {
  EXPECT_EQ(field("a,b"), "\"a,b\"");
  EXPECT_EQ(field(","), "\",\"");
}

TEST(CsvFieldTest, QuoteIsDoubledAndQuoted) {
  EXPECT_EQ(field("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(field("\""), "\"\"\"\"");
}

TEST(CsvFieldTest, LineBreaksAreQuoted) {
  EXPECT_EQ(field("line 1\nline 2"), "\"line 1\nline 2\"");
  EXPECT_EQ(field("ends\r\n"), "\"ends\r\n\"");
  EXPECT_EQ(field("cr\r"), "\"cr\r\"");
}

TEST(CsvFieldTest, QuotedFieldReadsBackAsTheOriginal) {
  for (const std::string s : {"a,b", "say \"hi\", twice: \"\"", "x\ny", "\"", ",\"\r\n"}) {
    const std::string q = field(s);
    ASSERT_GE(q.size(), 2u) << s;
    EXPECT_EQ(q.front(), '"') << s;
    EXPECT_EQ(q.back(), '"') << s;
    EXPECT_EQ(unquote(q), s);
  }
}

}  // namespace
}  // namespace telegrasp::csv
