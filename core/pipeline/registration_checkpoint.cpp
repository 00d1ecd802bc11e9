#include "core/pipeline/registration_checkpoint.h"

#include <cstring>
#include <type_traits>

namespace bathyslam {
namespace {

// Raised whenever a field of Constraint (or of what it holds) is added, removed or reordered.
constexpr std::uint32_t kVersion = 2;
// A tripwire for that: a field added to Constraint changes its size (GCC 12 and Clang 14 on
// Debian 12 alike). Write and read the new field below, raise kVersion, then this size.
static_assert(sizeof(Constraint) == 1696 && sizeof(Uniqueness) == 192 && sizeof(RegistrationQuality) == 32,
              "Constraint changed: keep registration_checkpoint.cpp's writer and reader in step");
// The probe's square is (2 reach + 1)² offsets (uniqueness.h): far beyond any search radius over
// step, and small enough that its side cannot overflow.
constexpr int kMaxReach = 1 << 15;
constexpr char kMagic[4] = {'B', 'S', 'R', 'B'};

class Writer {
 public:
  Writer() { bytes_.reserve(4096); }
  template <typename T>
  void put(const T& value) {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>);
    const std::size_t at = bytes_.size();
    bytes_.resize(at + sizeof(T));
    std::memcpy(bytes_.data() + at, &value, sizeof(T));
  }
  template <typename Derived>
  void put_matrix(const Eigen::MatrixBase<Derived>& m) {
    for (Eigen::Index i = 0; i < m.size(); ++i) put(static_cast<double>(m(i)));
  }
  void put(const std::string& text) {
    put(static_cast<std::uint32_t>(text.size()));
    const std::size_t at = bytes_.size();
    bytes_.resize(at + text.size());
    std::memcpy(bytes_.data() + at, text.data(), text.size());
  }
  void put(const std::vector<bool>& bits) {
    put(static_cast<std::uint32_t>(bits.size()));
    for (std::size_t i = 0; i < bits.size(); i += 8) {
      std::uint8_t byte = 0;
      for (std::size_t b = 0; b < 8 && i + b < bits.size(); ++b) byte |= static_cast<std::uint8_t>(bits[i + b]) << b;
      put(byte);
    }
  }
  std::vector<std::uint8_t> take() { return std::move(bytes_); }

 private:
  std::vector<std::uint8_t> bytes_;
};

class Reader {
 public:
  explicit Reader(const std::vector<std::uint8_t>& bytes) : bytes_(bytes) {}
  template <typename T>
  T get() {
    static_assert(std::is_arithmetic_v<T>);
    need(sizeof(T));
    T value;
    std::memcpy(&value, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }
  // An enum stored as int, within [0, last].
  template <typename E>
  E get_enum(E last) {
    const int value = get<int>();
    if (value < 0 || value > static_cast<int>(last)) throw CheckpointError("checkpoint: enum value out of range");
    return static_cast<E>(value);
  }
  template <typename Derived>
  void get_matrix(Eigen::MatrixBase<Derived>& m) {
    for (Eigen::Index i = 0; i < m.size(); ++i) m(i) = get<double>();
  }
  std::string get_string() {
    const std::uint32_t size = get<std::uint32_t>();
    need(size);
    std::string text(reinterpret_cast<const char*>(bytes_.data() + at_), size);
    at_ += size;
    return text;
  }
  std::vector<bool> get_bits() {
    const std::uint32_t size = get<std::uint32_t>();
    need((static_cast<std::size_t>(size) + 7) / 8);
    std::vector<bool> bits(size);
    for (std::size_t i = 0; i < size; ++i) bits[i] = (bytes_[at_ + i / 8] >> (i % 8)) & 1;
    at_ += (static_cast<std::size_t>(size) + 7) / 8;
    return bits;
  }
  bool at_end() const { return at_ == bytes_.size(); }

 private:
  void need(std::size_t n) const {
    if (bytes_.size() - at_ < n) throw CheckpointError("checkpoint: truncated");
  }
  const std::vector<std::uint8_t>& bytes_;
  std::size_t at_ = 0;
};

void put_isometry(Writer& w, const Eigen::Isometry3d& pose) { w.put_matrix(pose.matrix()); }

Eigen::Isometry3d get_isometry(Reader& r) {
  Eigen::Matrix4d m;
  r.get_matrix(m);
  Eigen::Isometry3d pose;
  pose.matrix() = m;
  return pose;
}

void put_rejection(Writer& w, const Rejection& rejection) {
  w.put(static_cast<int>(rejection.kind));
  w.put(rejection.detail);
}

Rejection get_rejection(Reader& r) {
  Rejection rejection;
  rejection.kind = r.get_enum(RejectionKind::kSafetyNet);
  rejection.detail = r.get_string();
  return rejection;
}

void put_uniqueness(Writer& w, const Uniqueness& u) {
  w.put(static_cast<std::uint8_t>(u.probed));
  for (double v : {u.cost_at_answer_m2, u.typical_cost_m2, u.local_cost_m2, u.alternative_cost_m2, u.nearby_cost_m2,
                   u.misfit_floor_m2, u.step_m})
    w.put(v);
  w.put_matrix(u.nearby_offset_m);
  w.put_matrix(u.alternative_offset_m);
  w.put(u.reach);
  w.put(u.competitors);
  w.put(u.open_competitors);
}

Uniqueness get_uniqueness(Reader& r) {
  Uniqueness u;
  u.probed = r.get<std::uint8_t>() != 0;
  for (double* v : {&u.cost_at_answer_m2, &u.typical_cost_m2, &u.local_cost_m2, &u.alternative_cost_m2,
                    &u.nearby_cost_m2, &u.misfit_floor_m2, &u.step_m})
    *v = r.get<double>();
  r.get_matrix(u.nearby_offset_m);
  r.get_matrix(u.alternative_offset_m);
  u.reach = r.get<int>();
  u.competitors = r.get_bits();
  u.open_competitors = r.get_bits();
  // competitor_offsets() walks the masks as a square of (2 reach + 1)² offsets.
  if (u.reach < 0 || u.reach > kMaxReach) throw CheckpointError("checkpoint: a uniqueness probe's reach out of range");
  const auto side = 2 * static_cast<std::size_t>(u.reach) + 1;
  for (const std::vector<bool>* mask : {&u.competitors, &u.open_competitors}) {
    if (!mask->empty() && mask->size() != side * side)
      throw CheckpointError("checkpoint: a uniqueness mask does not match its reach");
  }
  return u;
}

void put_constraint(Writer& w, const Constraint& c) {
  w.put(static_cast<int>(c.type));
  w.put(c.from);
  w.put(c.to);
  put_isometry(w, c.measured);
  w.put_matrix(c.anchor);
  put_isometry(w, c.guess);
  w.put_matrix(c.information);
  w.put_matrix(c.registered_information);
  w.put(static_cast<std::uint8_t>(c.quality.converged));
  w.put(c.quality.fitness);
  w.put(static_cast<std::uint64_t>(c.quality.overlap_points));
  w.put(c.quality.overlap_mse_m2);
  w.put(c.overlap_fraction);
  w.put(c.path ? static_cast<int>(*c.path) : -1);
  w.put(c.path_reason);
  w.put(c.feature_density);
  w.put(c.matches);
  w.put(c.inlier_ratio);
  w.put(c.competitor_inliers);
  w.put(c.competitor_separation_m);
  put_uniqueness(w, c.uniqueness);
  w.put(c.dr_mahalanobis2);
  w.put(c.horizontal_doubt);
  w.put_matrix(c.horizontal_spread);
  w.put(static_cast<int>(c.alias));
  w.put(c.alias_mahalanobis2);
  w.put_matrix(c.alias_spread_m);
  w.put(static_cast<std::uint8_t>(c.graph_information.has_value()));
  if (c.graph_information) w.put_matrix(*c.graph_information);
  put_rejection(w, c.rejection);
  put_rejection(w, c.exclusion);
}

Constraint get_constraint(Reader& r) {
  Constraint c;
  c.type = r.get_enum(ConstraintType::kDatum);
  c.from = r.get<int>();
  c.to = r.get<int>();
  c.measured = get_isometry(r);
  r.get_matrix(c.anchor);
  c.guess = get_isometry(r);
  r.get_matrix(c.information);
  r.get_matrix(c.registered_information);
  c.quality.converged = r.get<std::uint8_t>() != 0;
  c.quality.fitness = r.get<double>();
  c.quality.overlap_points = static_cast<std::size_t>(r.get<std::uint64_t>());
  c.quality.overlap_mse_m2 = r.get<double>();
  c.overlap_fraction = r.get<double>();
  const int path = r.get<int>();
  if (path < -1 || path > static_cast<int>(RegistrationPath::kFeatureAided))
    throw CheckpointError("checkpoint: registration path out of range");
  if (path >= 0) c.path = static_cast<RegistrationPath>(path);
  c.path_reason = r.get_string();
  c.feature_density = r.get<double>();
  c.matches = r.get<int>();
  c.inlier_ratio = r.get<double>();
  c.competitor_inliers = r.get<int>();
  c.competitor_separation_m = r.get<double>();
  c.uniqueness = get_uniqueness(r);
  c.dr_mahalanobis2 = r.get<double>();
  c.horizontal_doubt = r.get_string();
  r.get_matrix(c.horizontal_spread);
  c.alias = r.get_enum(AliasResolution::kJudgedByGraph);
  c.alias_mahalanobis2 = r.get<double>();
  r.get_matrix(c.alias_spread_m);
  if (r.get<std::uint8_t>() != 0) r.get_matrix(c.graph_information.emplace());
  c.rejection = get_rejection(r);
  c.exclusion = get_rejection(r);
  return c;
}

}  // namespace

std::vector<std::uint8_t> checkpoint_bytes(const RegisteredBatch& batch) {
  Writer w;
  for (char m : kMagic) w.put(m);
  w.put(kVersion);
  w.put(batch.begin);
  w.put(batch.end);
  w.put(static_cast<std::uint32_t>(batch.constraints.size()));
  for (const Constraint& c : batch.constraints) put_constraint(w, c);
  return w.take();
}

RegisteredBatch batch_from_checkpoint(const std::vector<std::uint8_t>& bytes) {
  Reader r(bytes);
  for (char m : kMagic) {
    if (r.get<char>() != m) throw CheckpointError("checkpoint: not a registered batch");
  }
  if (r.get<std::uint32_t>() != kVersion) throw CheckpointError("checkpoint: written by another version");
  RegisteredBatch batch;
  batch.begin = r.get<int>();
  batch.end = r.get<int>();
  const std::uint32_t count = r.get<std::uint32_t>();
  for (std::uint32_t k = 0; k < count; ++k) batch.constraints.push_back(get_constraint(r));
  if (!r.at_end()) throw CheckpointError("checkpoint: bytes after the last registration");
  return batch;
}

}  // namespace bathyslam
