#pragma once
// http (byte ranges): what a GET with a Range header answers (RFC 9110 §14). One range is served
// as asked, clamped to the resource; several are answered with the whole resource, which the RFC
// allows and which bounds what a request of a thousand small ranges costs; a range that starts
// beyond the end is refused.
#include <cstdint>
#include <string_view>

namespace bathyslam::server::http {

struct RangeAnswer {
  enum Kind { kWhole, kPartial, kUnsatisfiable } kind = kWhole;
  std::int64_t offset = 0, length = 0;  // kPartial: the bytes to send; kWhole: the resource
};

// The answer to `header` (the Range field's value; empty: none sent) for a resource of `size`
// bytes. A header in another unit or not of the RFC's syntax is ignored (the whole resource);
// but cpp-httplib answers 416 itself, before any handler, to a header its parser refuses
// (another unit, "Bytes", a space after "=", a range ending before it starts).
RangeAnswer answer_range(std::string_view header, std::int64_t size);

}  // namespace bathyslam::server::http
