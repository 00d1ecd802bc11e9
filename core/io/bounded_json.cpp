#include "core/io/bounded_json.h"

#include <string>

namespace bathyslam {

nlohmann::json parse_bounded_json(std::string_view text, const JsonLimits& limits) {
  if (text.size() > limits.max_bytes)
    throw JsonLimitError("larger than " + std::to_string(limits.max_bytes) + " bytes");
  // `depth` counts the containers around a value; throwing ends the parse before it goes deeper.
  auto guard = [&](int depth, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    const bool opens = event == nlohmann::json::parse_event_t::object_start ||
                       event == nlohmann::json::parse_event_t::array_start;
    if (opens && depth >= limits.max_depth)
      throw JsonLimitError("nested deeper than " + std::to_string(limits.max_depth) + " levels");
    // Keys and string values arrive here one by one, as they are parsed.
    const bool text = event == nlohmann::json::parse_event_t::key || event == nlohmann::json::parse_event_t::value;
    if (text && parsed.is_string() && parsed.get_ref<const std::string&>().find('\0') != std::string::npos)
      throw JsonLimitError("a string holds \\u0000 (NUL), which no stored text can hold");
    return true;
  };
  try {
    return nlohmann::json::parse(text, guard);
  } catch (const nlohmann::json::out_of_range& e) {
    // A number beyond a double's range ("6e524") is a limit too, not a crash (found by fuzzing).
    throw JsonLimitError(std::string("a number out of range: ") + e.what());
  }
}

}  // namespace bathyslam
