#include "server/scratch_dir.h"

#include <stdlib.h>

#include <stdexcept>
#include <string>

namespace bathyslam::server {

ScratchDir::ScratchDir(const std::filesystem::path& root, const std::string& prefix) {
  std::filesystem::create_directories(root);
  std::string pattern = (root / (prefix + ".XXXXXX")).string();
  if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("cannot make a scratch folder in " + root.string());
  path_ = pattern;
}

ScratchDir::~ScratchDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

}  // namespace bathyslam::server
