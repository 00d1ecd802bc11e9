#pragma once
// registration_checkpoint: one batch of the register stage's answers as bytes, so that a job
// stopped halfway (a server killed, a lease lost) can take up the registrations it had done
// instead of registering them again (docs/service.md, "Jobs that resume").
//
// A batch is stored as register_pairs gave it, before the later batches' judgements (the DR
// gate under a newer noise estimate, PCM) changed anything: those are replayed from it, so a
// resumed run repeats the uninterrupted one exactly. The bytes carry a layout version, not a
// build's identity; they are a cache, not an exchange format.
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/pipeline/constraint.h"

namespace bathyslam {

// The registrations of the candidates whose later submap lies in [begin, end).
struct RegisteredBatch {
  int begin = 0, end = 0;
  std::vector<Constraint> constraints;
};

// Bytes that are not a batch in this layout: the caller registers the batch again.
class CheckpointError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::vector<std::uint8_t> checkpoint_bytes(const RegisteredBatch& batch);
RegisteredBatch batch_from_checkpoint(const std::vector<std::uint8_t>& bytes);  // throws CheckpointError

// What a run takes up from an earlier one and how it keeps its own.
struct RegistrationCheckpoints {
  std::vector<RegisteredBatch> stored;  // from an earlier attempt of the same job, any order
  // Called with each batch the run registers itself, before the graph is solved with it.
  std::function<void(const RegisteredBatch&)> keep;
};

}  // namespace bathyslam
