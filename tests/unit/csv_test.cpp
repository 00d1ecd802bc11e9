#include "core/io/csv.h"

#include <gtest/gtest.h>

#include <array>
#include <string>

namespace bathyslam {
namespace {

std::vector<std::string> all_lines(std::string_view text, std::size_t block) {
  MemorySource source(text);
  LineReader reader(source, block);
  std::vector<std::string> lines;
  std::string_view line;
  while (reader.next(line)) lines.emplace_back(line);
  return lines;
}

TEST(LineReader, SplitsLinesAcrossBlockBoundariesAndLineEndings) {
  const std::string text = "a,b\r\nlonger line here\n\nlast";
  for (std::size_t block : {1, 2, 3, 7, 64}) {
    EXPECT_EQ(all_lines(text, block),
              (std::vector<std::string>{"a,b", "longer line here", "", "last"}))
        << "block " << block;
  }
}

TEST(LineReader, CountsLines) {
  MemorySource source("x\ny\nz\n");
  LineReader reader(source);
  std::string_view line;
  while (reader.next(line)) {}
  EXPECT_EQ(reader.line_number(), 3u);
}

TEST(SplitFields, CountsFieldsBeyondCapacity) {
  std::array<std::string_view, 2> fields;
  EXPECT_EQ(split_fields("1,2,3", fields), 3u);
  EXPECT_EQ(fields[0], "1");
  EXPECT_EQ(fields[1], "2");
  EXPECT_EQ(split_fields("", fields), 1u);
}

TEST(ParseNumber, RejectsGarbageAndNonFinite) {
  double d = 0;
  EXPECT_EQ(parse_number("12.5", d), NumberError::kNone);
  EXPECT_EQ(d, 12.5);
  EXPECT_EQ(parse_number("12.5x", d), NumberError::kNotANumber);
  EXPECT_EQ(parse_number("", d), NumberError::kNotANumber);
  EXPECT_EQ(parse_number("nan", d), NumberError::kNotFinite);
  EXPECT_EQ(parse_number("inf", d), NumberError::kNotFinite);
  EXPECT_EQ(parse_number("1e999", d), NumberError::kOutOfRange);
  uint32_t u = 0;
  EXPECT_EQ(parse_number("-1", u), NumberError::kNotANumber);
  EXPECT_EQ(parse_number("511", u), NumberError::kNone);
}

}  // namespace
}  // namespace bathyslam
