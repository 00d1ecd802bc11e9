#pragma once
// parallel: how our GICP's stages go parallel, kept apart from the
// algorithm (as small_gicp keeps its reductions apart from its factors). [0, n) is cut into one
// contiguous chunk per thread; each chunk fills its own accumulator and the caller sums them in
// chunk order, so a result depends on the thread count only through rounding.
#include <cstddef>
#include <functional>
#include <vector>

namespace bathyslam {

// Calls `work(chunk, begin, end)` once per chunk, on up to `threads` threads (1: inline, no
// OpenMP region). Returns the number of chunks (at least 1, at most max(n, 1)).
int parallel_chunks(std::size_t n, int threads, const std::function<void(int, std::size_t, std::size_t)>& work);

// One accumulator per chunk, summed with `+=` in chunk order: the reduction.
template <typename Accumulator, typename AddRange>
Accumulator parallel_sum(std::size_t n, int threads, AddRange&& add_range) {
  std::vector<Accumulator> partial(static_cast<std::size_t>(threads > 1 ? threads : 1));
  const int chunks = parallel_chunks(n, threads, [&](int chunk, std::size_t begin, std::size_t end) {
    add_range(partial[static_cast<std::size_t>(chunk)], begin, end);
  });
  for (int c = 1; c < chunks; ++c) partial[0] += partial[static_cast<std::size_t>(c)];
  return partial[0];
}

}  // namespace bathyslam
