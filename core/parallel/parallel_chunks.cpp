#include "core/parallel/parallel_chunks.h"

#include <algorithm>

namespace bathyslam {

int parallel_chunks(std::size_t n, int threads, const std::function<void(int, std::size_t, std::size_t)>& work) {
  const int chunks = static_cast<int>(std::clamp<std::size_t>(n, 1, static_cast<std::size_t>(std::max(threads, 1))));
  if (chunks == 1) {
    work(0, 0, n);
    return 1;
  }
#pragma omp parallel for schedule(static, 1) num_threads(chunks)
  for (int c = 0; c < chunks; ++c) {
    work(c, n * static_cast<std::size_t>(c) / chunks, n * static_cast<std::size_t>(c + 1) / chunks);
  }
  return chunks;
}

}  // namespace bathyslam
