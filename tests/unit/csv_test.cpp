#include "core/io/csv.h"

#include <gtest/gtest.h>

#include <algorithm>
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

TEST(LineReader, ALineOverTheLimitIsRefusedWithItsNumber) {
  const std::string text = "a\n" + std::string(LineReader::kMaxLineBytes, 'x') + "\n" +
                           std::string(LineReader::kMaxLineBytes + 1, 'y') + "\nz\n";
  for (std::size_t block : {std::size_t{7}, std::size_t{4} << 20}) {
    MemorySource source(text);
    LineReader reader(source, block);
    std::string_view line;
    ASSERT_TRUE(reader.next(line));
    ASSERT_TRUE(reader.next(line));  // exactly the limit is fine
    EXPECT_EQ(line.size(), LineReader::kMaxLineBytes);
    try {
      reader.next(line);
      FAIL() << "a line over the limit was returned (block " << block << ")";
    } catch (const LineTooLong& error) {
      EXPECT_EQ(error.line(), 3u);
    }
  }
}

// A source of endless bytes without a newline: the reader gives up after the limit instead of
// growing its buffer until memory runs out.
TEST(LineReader, AnEndlessLineIsRefusedWithoutReadingItAll) {
  struct Endless : ByteSource {
    std::size_t given = 0;
    std::size_t read(char* buffer, std::size_t size) override {
      std::fill(buffer, buffer + size, 'x');
      given += size;
      return size;
    }
  } source;
  LineReader reader(source, 4096);
  std::string_view line;
  EXPECT_THROW(reader.next(line), LineTooLong);
  EXPECT_LT(source.given, 4 * LineReader::kMaxLineBytes);
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
