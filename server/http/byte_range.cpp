#include "server/http/byte_range.h"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <optional>

namespace bathyslam::server::http {
namespace {

std::optional<std::int64_t> number(std::string_view text) {
  std::int64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc() || end != text.data() + text.size() || value < 0) return std::nullopt;
  return value;
}

bool starts_with_unit(std::string_view header) {
  constexpr std::string_view kUnit = "bytes=";
  return header.size() >= kUnit.size() &&
         std::equal(kUnit.begin(), kUnit.end(), header.begin(), [](char a, char b) { return a == (b | 0x20); });
}

}  // namespace

RangeAnswer answer_range(std::string_view header, std::int64_t size) {
  const RangeAnswer whole{RangeAnswer::kWhole, 0, size};
  if (!starts_with_unit(header)) return whole;
  std::string_view spec = header.substr(6);
  while (!spec.empty() && spec.front() == ' ') spec.remove_prefix(1);
  while (!spec.empty() && spec.back() == ' ') spec.remove_suffix(1);
  if (spec.find(',') != std::string_view::npos) return whole;
  const std::size_t dash = spec.find('-');
  if (dash == std::string_view::npos) return whole;
  const std::string_view first = spec.substr(0, dash), last = spec.substr(dash + 1);
  const RangeAnswer unsatisfiable{RangeAnswer::kUnsatisfiable, 0, 0};
  if (first.empty()) {  // the last n bytes
    const std::optional<std::int64_t> n = number(last);
    if (!n) return whole;
    if (*n == 0 || size == 0) return unsatisfiable;
    const std::int64_t length = std::min(*n, size);
    return {RangeAnswer::kPartial, size - length, length};
  }
  const std::optional<std::int64_t> from = number(first);
  const std::optional<std::int64_t> to = last.empty() ? std::optional<std::int64_t>(INT64_MAX) : number(last);
  if (!from || !to || *to < *from) return whole;
  if (*from >= size) return unsatisfiable;
  return {RangeAnswer::kPartial, *from, std::min(*to, size - 1) - *from + 1};
}

}  // namespace bathyslam::server::http
