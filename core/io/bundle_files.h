#pragma once
// Where a survey bundle's files live: a folder, or a .tar of one (docs/design.md, "Survey bundle"),
// read in place through GDAL's /vsitar/ file system, nothing extracted.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "core/io/byte_source.h"

namespace bathyslam {

// Where a bundle's files are read from: a folder or a tar (BundleFiles), or wherever a caller
// keeps them (the server reads an upload straight from its database).
class BundleSource {
 public:
  virtual ~BundleSource() = default;
  virtual bool contains(std::string_view file) const = 0;
  // The file's bytes; throws std::runtime_error naming the file.
  virtual std::unique_ptr<ByteSource> open(std::string_view file) const = 0;
  // The bundle as a user knows it, for messages ("missing from NAME").
  virtual std::string name() const = 0;
};

class BundleFiles : public BundleSource {
 public:
  // A folder, or a file taken as a tar whose survey.json may sit in a folder of its own (a tar
  // of the bundle folder). Throws std::runtime_error naming the bundle when it does not exist,
  // is no tar, or holds no survey.json or more than one.
  explicit BundleFiles(const std::filesystem::path& bundle);

  bool contains(std::string_view file) const override;
  std::uint64_t size(std::string_view file) const;  // throws naming the file
  std::unique_ptr<ByteSource> open(std::string_view file) const override { return open(file, 0); }
  // The file's bytes from `offset` on; throws std::runtime_error naming the file.
  std::unique_ptr<ByteSource> open(std::string_view file, std::uint64_t offset) const;
  std::string name() const override { return bundle_.string(); }

 private:
  std::string path_of(std::string_view file) const;

  std::filesystem::path bundle_;
  std::string tar_root_;  // "/vsitar/BUNDLE/DIR" inside a tar; empty for a folder
};

}  // namespace bathyslam
