#pragma once
// The members of a tar as its headers declare them. GDAL's /vsitar/, which reads a bundle's
// files in place, does not say what a member is: it lists a symbolic link, a hard link or a
// device as a file of 0 bytes, and reading one runs on into the headers that follow. A bundle
// is checked with this first (BundleFiles), so that nothing is taken for a file that is not one.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace bathyslam {

struct TarMember {
  std::string name;  // as the header (or a GNU long-name or pax "path" record) gives it
  char type = '0';   // the ustar typeflag: '0' file, '1' hard link, '2' symbolic link, '5' folder, ...
  std::string link;  // the target of a link
};

// Every member of the tar at `tar`, in order, the pax and GNU extension headers folded into the
// member they describe. Stops at the end-of-archive block or where the file ends.
std::vector<TarMember> tar_members(const std::filesystem::path& tar);

// The first member that is neither a regular file nor a folder, said in words ("b/pings.csv is a
// symbolic link to '/etc/passwd'"), or nullopt when there is none.
std::optional<std::string> tar_member_not_a_file(const std::vector<TarMember>& members);

}  // namespace bathyslam
