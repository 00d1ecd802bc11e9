// libFuzzer target for a bundle given as a .tar (`bathyslam process x.tar`, `upload x.tar`): the
// bytes as the tar, opened as BundleFiles opens one (our walk of its headers, then GDAL's
// /vsitar/), and every bundle file it offers read through. Any bytes must end in a refusal or in
// files, never a crash, a hang, a leak or a sanitizer report (scripts/fuzz-bundle.sh tar).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/io/bundle.h"
#include "core/io/bundle_files.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace bathyslam;
  // A new name each time: GDAL keeps what it read of an archive by its name.
  static int count = 0;
  const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                     ("bathyslam-tar-fuzz-" + std::to_string(getpid()) + "-" + std::to_string(count++) + ".tar");
  {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    const BundleFiles files(path);
    for (const std::string_view name : {kSurveyJsonFile, kNavFile, kPingsFile, kReferenceNavFile}) {
      if (!files.contains(name)) continue;
      const std::uint64_t declared = files.size(name);
      std::unique_ptr<ByteSource> source = files.open(name);
      std::vector<char> buffer(4096);
      std::uint64_t read = 0;
      while (const std::size_t got = source->read(buffer.data(), buffer.size())) {
        read += got;
        if (read > declared || read > (1u << 20)) break;  // a member reads no more than it declares
      }
    }
  } catch (const std::exception&) {
    // refused with the bundle's name: what BundleFiles must do with a damaged tar
  }
  std::filesystem::remove(path);
  return 0;
}
