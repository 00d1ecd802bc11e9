#include "core/io/bundle_files.h"

#include <algorithm>
#include <stdexcept>
#include <vector>

#include <cpl_string.h>
#include <cpl_vsi.h>

#include "core/io/tar_members.h"

namespace bathyslam {
namespace {

// A member of a tar, through GDAL's virtual file system, read up to its size and no further:
// GDAL reads an empty member on into the headers after it, whose bytes are not the file's.
class VsiSource : public ByteSource {
 public:
  VsiSource(const std::string& path, std::string_view name, std::uint64_t offset, std::uint64_t size)
      : file_(VSIFOpenL(path.c_str(), "rb")), left_(size > offset ? size - offset : 0) {
    if (file_ == nullptr || VSIFSeekL(file_, offset, SEEK_SET) != 0) {
      if (file_ != nullptr) VSIFCloseL(file_);
      throw std::runtime_error(std::string(name) + ": cannot be read from the tar");
    }
  }
  ~VsiSource() override { VSIFCloseL(file_); }
  VsiSource(const VsiSource&) = delete;
  VsiSource& operator=(const VsiSource&) = delete;
  std::size_t read(char* buffer, std::size_t size) override {
    const std::size_t got = VSIFReadL(buffer, 1, static_cast<std::size_t>(std::min<std::uint64_t>(size, left_)), file_);
    left_ -= got;
    return got;
  }

 private:
  VSILFILE* file_;
  std::uint64_t left_;  // bytes of the member not read yet
};

// The folder inside a tar that holds survey.json ("" at the top).
std::string folder_of_survey_json(const std::filesystem::path& tar) {
  const std::string root = "/vsitar/" + tar.string();
  char** entries = VSIReadDirRecursive(root.c_str());
  if (entries == nullptr) throw std::runtime_error(tar.string() + ": neither a folder nor a tar");
  std::vector<std::string> found;
  for (char** e = entries; *e != nullptr; ++e) {
    const std::filesystem::path entry(*e);
    if (entry.filename() != "survey.json") continue;
    // GDAL lists pax extended headers (GNU tar --format=pax, macOS tars with attributes) as
    // files of their own, "PaxHeaders.N/survey.json"; they are not the bundle's.
    const bool pax_header = std::any_of(entry.begin(), entry.end(), [](const std::filesystem::path& part) {
      return part.string().rfind("PaxHeader", 0) == 0;
    });
    if (!pax_header) found.push_back(entry.parent_path().string());
  }
  CSLDestroy(entries);
  if (found.empty()) throw std::runtime_error(tar.string() + ": the tar holds no survey.json");
  if (found.size() > 1) {
    throw std::runtime_error(tar.string() + ": the tar holds " + std::to_string(found.size()) +
                             " survey.json files (one bundle per tar)");
  }
  return found.front();
}

}  // namespace

BundleFiles::BundleFiles(const std::filesystem::path& bundle) : bundle_(bundle) {
  if (std::filesystem::is_directory(bundle)) return;
  if (!std::filesystem::exists(bundle)) throw std::runtime_error(bundle.string() + ": no such folder or tar");
  const std::string folder = folder_of_survey_json(bundle);
  // Nothing is followed: a link's bytes are not in the tar, yet GDAL would offer some.
  if (auto problem = tar_member_not_a_file(tar_members(bundle)))
    throw std::runtime_error(bundle.string() + ": " + *problem +
                             "; a bundle's tar holds files and folders only (tar --dereference stores what links point to)");
  tar_root_ = "/vsitar/" + bundle.string() + (folder.empty() ? "" : "/" + folder);
}

std::string BundleFiles::path_of(std::string_view file) const {
  return tar_root_.empty() ? (bundle_ / file).string() : tar_root_ + "/" + std::string(file);
}

bool BundleFiles::contains(std::string_view file) const {
  if (tar_root_.empty()) return std::filesystem::exists(bundle_ / file);
  VSIStatBufL stat;
  return VSIStatL(path_of(file).c_str(), &stat) == 0;
}

std::uint64_t BundleFiles::size(std::string_view file) const {
  if (tar_root_.empty()) return std::filesystem::file_size(bundle_ / file);
  VSIStatBufL stat;
  if (VSIStatL(path_of(file).c_str(), &stat) != 0) throw std::runtime_error(std::string(file) + ": not in " + name());
  return static_cast<std::uint64_t>(stat.st_size);
}

std::unique_ptr<ByteSource> BundleFiles::open(std::string_view file, std::uint64_t offset) const {
  if (tar_root_.empty()) return std::make_unique<FileSource>(bundle_ / file, offset);
  return std::make_unique<VsiSource>(path_of(file), file, offset, size(file));
}

}  // namespace bathyslam
