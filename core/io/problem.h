#pragma once
// A problem found in an input: where it is (file, line, field) and what is wrong.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace bathyslam {

struct Problem {
  enum class Severity { kError, kWarning };
  Severity severity = Severity::kError;
  std::string file;      // empty when the bundle as a whole is at fault; the message names it
  std::size_t line = 0;  // 1-based; 0 when the problem is about the whole file
  std::string field;     // column or JSON key; empty when the whole line or file is at fault
  std::string message;

  // "nav.csv:12: heading: not a number: 'abc'"
  std::string to_string() const;
};

// Collects problems, keeping at most `max_per_file` per file so a file with a million bad lines
// still yields a readable report (the count of the rest is kept).
class ProblemList {
 public:
  explicit ProblemList(std::size_t max_per_file = 50) : max_per_file_(max_per_file) {}

  void error(std::string file, std::size_t line, std::string field, std::string message);
  void warning(std::string file, std::size_t line, std::string field, std::string message);

  bool has_errors() const { return errors_ > 0; }
  std::size_t error_count() const { return errors_; }
  // The kept problems, followed by one note per file whose problems were cut.
  std::vector<Problem> take();
  // `later`'s problems after these, as if reported here (a file read on another thread).
  void append(ProblemList later);

 private:
  void add(Problem problem);

  std::size_t max_per_file_;
  std::size_t errors_ = 0;
  std::vector<Problem> problems_;
  std::vector<std::pair<std::string, std::size_t>> dropped_;  // file, count
};

// `text` as printable UTF-8: control characters and bytes that are not UTF-8 become "\xNN".
// Input quoted into a message passes through this, so that a file of NUL bytes or Latin-1 makes
// a message every terminal, JSON encoder and database column can hold.
std::string printable(std::string_view text);

// How every message quotes a user's input: printable, between quotes, and at most the first
// `kQuotedBytes` bytes of it followed by "…' (N bytes)", so that a 2 MB file name cannot make a
// status trailer larger than gRPC's metadata limit, nor a log line of megabytes.
inline constexpr std::size_t kQuotedBytes = 64;
std::string quoted_input(std::string_view text);

}  // namespace bathyslam
