#pragma once
// Whole-file writes of encoded bytes (PNG and the like).
#include <cstdint>
#include <filesystem>
#include <span>

namespace bathyslam {

// Writes `bytes` to `path`, replacing it; throws std::runtime_error naming the path on failure.
void write_file_bytes(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);

}  // namespace bathyslam
