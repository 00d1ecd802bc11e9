#include "core/io/tar_members.h"

#include <algorithm>
#include <array>
#include <fstream>
#include <string_view>

#include "core/io/problem.h"

namespace bathyslam {
namespace {

constexpr std::size_t kBlock = 512;
using Header = std::array<char, kBlock>;

// A NUL-terminated field of a header.
std::string field(const Header& header, std::size_t offset, std::size_t length) {
  const char* begin = header.data() + offset;
  return std::string(begin, std::find(begin, begin + length, '\0'));
}

// The size field: octal digits, or GNU's base-256 (first byte's high bit set) for 8 GiB and more.
std::uint64_t member_size(const Header& header) {
  const auto* size = reinterpret_cast<const unsigned char*>(header.data() + 124);
  std::uint64_t value = 0;
  if (size[0] & 0x80) {
    for (std::size_t i = 1; i < 12; ++i) value = (value << 8) | size[i];
    return value;
  }
  for (std::size_t i = 0; i < 12 && size[i] >= '0' && size[i] <= '7'; ++i) value = value * 8 + (size[i] - '0');
  return value;
}

// A ustar name: the prefix field, when the magic says there is one, then the name field.
std::string member_name(const Header& header) {
  const std::string name = field(header, 0, 100);
  if (std::string_view(header.data() + 257, 6) != std::string_view("ustar\0", 6)) return name;
  const std::string prefix = field(header, 345, 155);
  return prefix.empty() ? name : prefix + "/" + name;
}

// The "path" and "linkpath" records of a pax extended header ("LEN key=value\n" each).
void apply_pax(std::string_view records, std::string& path, std::string& link_path) {
  while (!records.empty()) {
    const std::size_t space = records.find(' ');
    std::size_t length = 0;
    for (std::size_t i = 0; i < space && i < records.size() && records[i] >= '0' && records[i] <= '9'; ++i)
      length = length * 10 + static_cast<std::size_t>(records[i] - '0');
    if (space == std::string_view::npos || length <= space + 1 || length > records.size()) return;
    const std::string_view record = records.substr(space + 1, length - space - 2);  // without the '\n'
    const std::size_t equals = record.find('=');
    if (equals != std::string_view::npos) {
      if (record.substr(0, equals) == "path") path = record.substr(equals + 1);
      if (record.substr(0, equals) == "linkpath") link_path = record.substr(equals + 1);
    }
    records.remove_prefix(length);
  }
}

bool all_zero(const Header& header) {
  return std::all_of(header.begin(), header.end(), [](char c) { return c == '\0'; });
}

}  // namespace

std::vector<TarMember> tar_members(const std::filesystem::path& tar) {
  std::ifstream in(tar, std::ios::binary);
  std::error_code error;
  const std::uint64_t length = std::filesystem::file_size(tar, error);
  std::vector<TarMember> members;
  std::string long_name, long_link;  // from GNU 'L'/'K' or pax 'x' headers, for the next member
  Header header;
  while (in.read(header.data(), kBlock) && !all_zero(header)) {
    const char type = header[156];
    const std::uint64_t size = member_size(header);
    // A member that runs past the file's end ends the walk: its size, rounded up, could wrap and
    // seek back to this header again, forever (found by fuzzing: a base-256 size of 2^64 - 1).
    const std::uint64_t here = static_cast<std::uint64_t>(in.tellg());
    if (error || size > length || (size + kBlock - 1) / kBlock * kBlock > length - here) break;
    const std::uint64_t padded = (size + kBlock - 1) / kBlock * kBlock;
    if (type == 'L' || type == 'K' || type == 'x') {
      std::string data(static_cast<std::size_t>(std::min<std::uint64_t>(size, 1 << 20)), '\0');
      if (!in.read(data.data(), static_cast<std::streamsize>(data.size()))) break;
      in.seekg(static_cast<std::streamoff>(padded - data.size()), std::ios::cur);
      if (type == 'L') long_name = data.c_str();
      if (type == 'K') long_link = data.c_str();
      if (type == 'x') apply_pax(data, long_name, long_link);
      continue;
    }
    TarMember member{long_name.empty() ? member_name(header) : long_name, type == '\0' ? '0' : type,
                     long_link.empty() ? field(header, 157, 100) : long_link};
    long_name.clear();
    long_link.clear();
    if (type != 'g') members.push_back(std::move(member));  // 'g': pax global settings, no member
    in.seekg(static_cast<std::streamoff>(padded), std::ios::cur);
  }
  return members;
}

std::optional<std::string> tar_member_not_a_file(const std::vector<TarMember>& members) {
  // The user's own tar, told to the user: the whole path, whose end names the bundle's file.
  const auto quoted = [](const std::string& path) { return "'" + printable(path) + "'"; };
  for (const TarMember& member : members) {
    switch (member.type) {
      case '0':
      case '7':  // contiguous file: a regular file to every reader
      case '5': continue;
      case '1': return quoted(member.name) + " is a hard link to " + quoted(member.link);
      case '2': return quoted(member.name) + " is a symbolic link to " + quoted(member.link);
      case '3': return quoted(member.name) + " is a character device";
      case '4': return quoted(member.name) + " is a block device";
      case '6': return quoted(member.name) + " is a named pipe";
      default: return quoted(member.name) + " is of tar type '" + printable(std::string(1, member.type)) + "', not a file";
    }
  }
  return std::nullopt;
}

}  // namespace bathyslam
