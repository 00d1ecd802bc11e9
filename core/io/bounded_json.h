#pragma once
// JSON that comes from outside (a request field, survey.json) parsed with limits on its size and
// nesting. nlohmann's parser is iterative, but copying or dumping a value recurses once per
// level, so a document nested 100 000 deep parses fine and exhausts the stack later, far from
// the input. The library has no depth option; its parser callback is told the depth of every
// value, which is where the limit is enforced, before the value exists.
#include <cstddef>
#include <stdexcept>
#include <string_view>

#include <nlohmann/json.hpp>

namespace bathyslam {

struct JsonLimits {
  std::size_t max_bytes = 1 << 20;
  int max_depth = 64;  // objects and arrays inside one another
};

// A document over a limit; the message says which ("nested deeper than 64 levels").
class JsonLimitError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws JsonLimitError over a limit, for a string or key holding U+0000 ("\u0000" is valid
// JSON, but PostgreSQL's jsonb and text refuse it: the survey could not be stored), and
// nlohmann::json::parse_error for a syntax error.
nlohmann::json parse_bounded_json(std::string_view text, const JsonLimits& limits = {});

}  // namespace bathyslam
