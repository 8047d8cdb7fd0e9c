// LevelCheckpoint files: the state between two levels of a coarse-to-fine run (match --checkpoint).
// Raw values in the host's byte order: a checkpoint goes on on the kind of machine that wrote it.
#include "shapematch/coarse_to_fine.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/files.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <new>
#include <type_traits>

namespace shapematch {
namespace {

constexpr char kMagic[] = "shapematch level checkpoint\n";
// 2: the attempt of the level in progress (LevelAttempt) follows the extra rings. 3: its
// rounding (LevelAttempt::Rounding) follows the attempt. 4: LevelReport::stuck_restarts. 5: the
// lookahead's chains (LevelCheckpoint::chains) follow. 6: each chain's attempt follows it. 7:
// LevelReport::lookahead_other_bound and lookahead_other_stuck. 8: branch_roundings,
// branch_energy and branch_kept. 9: LevelAttempt::zero_cost_margin_given follows `trusted`.
// 10: LevelAttempt::Rounding::steps follows its ones. 11: LevelAttempt::suspicion_margins
// follows zero_cost_margin_given. 12: LevelAttempt::Rounding::cap_scale follows its steps. 13:
// LevelAttempt::priced_from and solving (each a flag, then its parts; solving's iterations and
// re-solve flag; where either, the cold solve's iterations and seconds) follow the rounding.
// 14: LevelAttempt::Rounding::warm (a flag, then its parts) follows its cap_scale, and the LP
// under way's seconds and watch flag follow its iterations and re-solve flag. 1 to 13 are read
// too (13 as written by the seventy-eighth session's binaries of 4512e6d-a25eb65; its other
// intermediate layouts of 13 are refused as cut short or malformed).
// 15: the layout of 14; a rounding's lower_bound may be NaN (an attempt gone on from a stuck
// rounding's fixings, whose round 1 bounds no whole LP), which binaries before 2267cca would take
// for a bound: they refuse the file instead. (Binaries of 2267cca-fdfdc89 wrote such a NaN as 14
// and read it as this one does.)
// 16: an LP under way's divergence watch (LevelAttempt::solving_watch) follows its watch flag.
// 17: LevelReport::proof_rechecks; an attempt's last local proof region (proof_faces, proof_rings).
// 18: the layout of 17, then a checksum (Checksum) of every byte before it.
// 19: an LP under way's whole state (LevelAttempt::solving_state: a flag, then write_state's
// layout) follows its watch. (As 672ff1a wrote it, without the device, it is refused: only that
// commit's binaries, within the eighty-ninth session, wrote it.)
// 20: the local proof region's size at its last recheck (proof_rows, proof_cols) follows its rings.
constexpr uint32_t kVersion = 20;
constexpr uint32_t kFirstChecksummed = 18;
// More rings than a local proof's region grows (RoundingOptions::local_proof_depth).
constexpr int kMaxProofRings = 64;
// More LP iterations than any solve makes (a count past it is a corrupt file, and would overflow).
constexpr int64_t kMaxIterations = int64_t(1) << 40;

// Every number of a report, in the file's order (the Γ follows on its own). A field added to
// LevelReport goes here too, with kVersion one higher; the size check below is the reminder.
template <class R, class F>
void each_field(R& r, F&& f, uint32_t version) {
  f(r.level), f(r.faces_x), f(r.faces_y), f(r.variables), f(r.full_variables), f(r.constraints), f(r.ring);
  f(r.widenings), f(r.local_widenings), f(r.margin_widenings), f(r.widened_faces), f(r.stuck_widenings);
  if (version >= 4) f(r.stuck_restarts);
  f(r.price_widenings), f(r.propagation_widenings), f(r.recurring_widenings), f(r.inherited_faces);
  f(r.carried_fixings), f(r.iterations_bound), f(r.rounds), f(r.iterations), f(r.lower_bound), f(r.energy);
  f(r.gap), f(r.threshold), f(r.roundings), f(r.seconds), f(r.peak_rss_mb), f(r.second_start_energy);
  f(r.second_start_kept), f(r.lookahead_other_energy), f(r.lookahead_switched);
  if (version >= 7) f(r.lookahead_other_bound), f(r.lookahead_other_stuck);
  if (version >= 8) f(r.branch_roundings), f(r.branch_energy), f(r.branch_kept);
  if (version >= 17) f(r.proof_rechecks);
}
// (It misses a new int or bool that fits in padding: LevelReport's comment asks for this list too.)
static_assert(sizeof(LevelReport) == 248 + sizeof(std::vector<ProductTriangle>),
              "LevelReport changed: add the new field to each_field and raise kVersion");

// A checksum of a file's bytes (version 18 on): a byte changed on disk or in a copy, or a file
// cut short, is refused as damaged rather than read (a flipped byte of an iterate had gone on as
// another warm start; the audit of the eighty-seventh session). Not against forgery. Each 8-byte
// word goes through steps that are one-to-one in the state and in the word, so a file differing
// in one word always differs in its checksum; the length is mixed in at the end.
class Checksum {
public:
  void add(const char* p, size_t n) {
    length_ += n;
    while (n > 0) {
      if (fill_ == 0 && n >= 8) {  // (the bulk: arrays of millions of values)
        uint64_t w;
        std::memcpy(&w, p, 8);
        mix(w);
        p += 8, n -= 8;
        continue;
      }
      pending_[fill_++] = *p++, --n;
      if (fill_ == 8) {
        uint64_t w;
        std::memcpy(&w, pending_, 8);
        mix(w);
        fill_ = 0;
      }
    }
  }
  uint64_t value() const {
    Checksum c = *this;
    uint64_t w = 0;
    std::memcpy(&w, pending_, fill_);
    c.mix(w);  // (the tail, zero-padded; then the length, so that padding and length never trade)
    c.mix(length_);
    uint64_t h = c.h_;  // (splitmix64's finaliser: every bit of the state reaches every bit)
    h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;
    h = (h ^ (h >> 27)) * 0x94D049BB133111EBull;
    return h ^ (h >> 31);
  }

private:
  void mix(uint64_t w) { h_ = std::rotl(h_ ^ (w * 0x9E3779B97F4A7C15ull), 29) * 0xD6E8FEB86659FD93ull; }
  uint64_t h_ = 0x736D6174636831ull;
  uint64_t length_ = 0;
  char pending_[8] = {};
  size_t fill_ = 0;
};

class Writer {
public:
  explicit Writer(std::ostream& out) : out_(out) {}
  template <class T>
  void operator()(const T& v) {
    static_assert(std::is_arithmetic_v<T>);
    if constexpr (std::is_same_v<T, bool>) {
      const uint8_t b = v ? 1 : 0;
      put(reinterpret_cast<const char*>(&b), 1);
    } else {
      put(reinterpret_cast<const char*>(&v), sizeof v);
    }
  }
  template <class T>
  void array(const std::vector<T>& v) {
    (*this)(uint64_t(v.size()));
    put(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  void put(const char* p, size_t n) {
    out_.write(p, std::streamsize(n));
    sum_.add(p, n);
  }
  // The checksum of everything written so far, after it (not itself summed).
  void seal() {
    const uint64_t v = sum_.value();
    out_.write(reinterpret_cast<const char*>(&v), sizeof v);
  }

private:
  std::ostream& out_;
  Checksum sum_;
};

class Reader {
public:
  Reader(const std::string& path, std::string bytes) : path_(path), bytes_(std::move(bytes)) {}
  template <class T>
  void operator()(T& v) {
    static_assert(std::is_arithmetic_v<T>);
    take(&v, sizeof v);
  }
  void operator()(bool& v) {  // (any byte but 0 and 1 would be undefined as a bool)
    uint8_t b = 0;
    take(&b, 1);
    if (b > 1) throw IoError(path_ + ": not a shapematch checkpoint (a flag of " + std::to_string(b) + ")");
    v = b == 1;
  }
  template <class T>
  void array(std::vector<T>& v) {
    uint64_t n = 0;
    (*this)(n);
    if (n > (bytes_.size() - at_) / sizeof(T)) short_file();  // before allocating
    v.resize(n);
    take(v.data(), n * sizeof(T));
  }
  void take(void* to, size_t n) {
    if (n > bytes_.size() - at_) short_file();
    std::memcpy(to, bytes_.data() + at_, n);
    at_ += n;
  }
  bool done() const { return at_ == bytes_.size(); }
  [[noreturn]] void short_file() const { throw IoError(path_ + ": the checkpoint is cut short"); }

private:
  std::string path_;
  std::string bytes_;
  size_t at_ = 0;
};

static_assert(std::is_trivially_copyable_v<ProductTriangle> && sizeof(ProductTriangle) == 8 * sizeof(int));

// Level reports, each followed by its Γ (the count is the caller's).
void write_levels(Writer& w, const std::vector<LevelReport>& levels, uint32_t version) {
  for (const LevelReport& r : levels) {
    each_field(r, w, version);
    w.array(r.gamma);
  }
}
void read_levels(Reader& r, std::vector<LevelReport>& levels, uint64_t count, uint32_t version) {
  levels.resize(count);
  for (LevelReport& rep : levels) {
    each_field(rep, r, version);
    r.array(rep.gamma);
  }
}

// A warm start kept with an attempt (version >= 13): CarriedIterate::Parts.
void write_iterate(Writer& w, const CarriedIterate& c) {
  const auto& x = c.values_by_key();  // (as Parts: keys, then values; no copy of either)
  w(uint64_t(x.size()));
  for (const auto& kv : x) w(kv.first);
  w(uint64_t(x.size()));
  for (const auto& kv : x) w(kv.second);
  w.array(c.row_edges()), w.array(c.duals());
  w(c.closedness_rows()), w(c.scale()), w(c.primal_weight());
}
CarriedIterate read_iterate(Reader& r, const std::string& path) {
  CarriedIterate::Parts p;
  r.array(p.keys), r.array(p.values), r.array(p.row_edge), r.array(p.y);
  r(p.closedness_rows), r(p.scale), r(p.primal_weight);
  try {
    return CarriedIterate::from_parts(std::move(p));
  } catch (const InvalidInputError& e) {
    throw IoError(path + ": not a shapematch checkpoint (" + e.what() + ")");
  }
}

// An LP under way's divergence watch (version >= 16).
void write_watch(Writer& w, const DivergenceWatchState& s) {
  w(s.windows), w(s.creeping), w(s.climbing), w(s.primal), w(s.gap), w(s.bound), w(s.excess[0]), w(s.excess[1]);
}
DivergenceWatchState read_watch(Reader& r, const std::string& path) {
  DivergenceWatchState s;
  r(s.windows), r(s.creeping), r(s.climbing), r(s.primal), r(s.gap), r(s.bound), r(s.excess[0]), r(s.excess[1]);
  const bool counts = s.windows >= 0 && s.creeping >= 0 && s.climbing >= 0 && s.creeping <= s.windows &&
                      s.climbing <= s.windows;
  // (An infeasible LP's bound may be huge, not infinite: the watch compares what it saw.)
  if (!counts || !std::isfinite(s.primal) || !std::isfinite(s.gap) || !std::isfinite(s.bound) ||
      !std::isfinite(s.excess[0]) || !std::isfinite(s.excess[1]))
    throw IoError(path + ": not a shapematch checkpoint (an LP under way's divergence watch after " +
                  std::to_string(s.windows) + " windows)");
  return s;
}

// A vector of mostly +0.0 (a PDHG iterate's columns: most product triangles are at their bound 0,
// bit for bit): its size, then the indices and values of the others.
void write_mostly_zero(Writer& w, const std::vector<double>& v) {
  std::vector<uint64_t> at;
  std::vector<double> value;
  for (size_t j = 0; j < v.size(); ++j)
    if (std::bit_cast<uint64_t>(v[j]) != 0) at.push_back(j), value.push_back(v[j]);
  w(uint64_t(v.size()));
  w.array(at), w.array(value);
}
void read_mostly_zero(Reader& r, std::vector<double>& v, const std::string& path) {
  uint64_t n = 0;
  r(n);
  std::vector<uint64_t> at;
  std::vector<double> value;
  r.array(at), r.array(value);
  // (A size past any LP's, 31-bit columns, is a corrupt file: refused before it is allocated.
  // Indices as written: increasing.)
  bool increasing = true;
  for (size_t k = 0; k < at.size(); ++k) increasing = increasing && at[k] < n && (k == 0 || at[k - 1] < at[k]);
  if (n >= (uint64_t(1) << 31) || at.size() != value.size() || !increasing)
    throw IoError(path + ": not a shapematch checkpoint (an LP state's vector of " + std::to_string(n) + " values)");
  try {
    v.assign(n, 0.0);
  } catch (const std::bad_alloc&) {
    throw IoError(path + ": an LP state's vector of " + std::to_string(n) + " values does not fit in memory");
  }
  for (size_t k = 0; k < at.size(); ++k) v[at[k]] = value[k];
}

// An LP under way's whole state (version >= 19).
void write_state(Writer& w, const SolverState& s) {
  w.array(std::vector<char>(s.solver.begin(), s.solver.end()));
  w.array(std::vector<char>(s.device.begin(), s.device.end()));
  w(s.fingerprint);
  write_mostly_zero(w, s.x), write_mostly_zero(w, s.x0);
  w.array(s.y), w.array(s.y0), w.array(s.window_y);
  w(s.step), w(s.primal_weight), w(s.restart_artificial), w(s.restart_base), w(s.previous);
  w(s.since_restart), w(s.iterations), w(s.window_left), w(s.restarts);
  write_watch(w, s.watch);
}
std::shared_ptr<const SolverState> read_state(Reader& r, const std::string& path) {
  auto s = std::make_shared<SolverState>();
  std::vector<char> name;
  r.array(name);
  s->solver.assign(name.begin(), name.end());
  r.array(name);
  s->device.assign(name.begin(), name.end());
  r(s->fingerprint);
  read_mostly_zero(r, s->x, path), read_mostly_zero(r, s->x0, path);
  r.array(s->y), r.array(s->y0), r.array(s->window_y);
  r(s->step), r(s->primal_weight), r(s->restart_artificial), r(s->restart_base), r(s->previous);
  r(s->since_restart), r(s->iterations), r(s->window_left), r(s->restarts);
  s->watch = read_watch(r, path);
  // (`previous` may be +∞: no residual since the last restart.)
  const bool sizes = s->x.size() == s->x0.size() && s->y.size() == s->y0.size() &&
                     (s->window_y.empty() || s->window_y.size() == s->y.size());
  const bool scalars = std::isfinite(s->step) && s->step > 0.0 && std::isfinite(s->primal_weight) &&
                       s->primal_weight > 0.0 && std::isfinite(s->restart_artificial) &&
                       std::isfinite(s->restart_base) && !std::isnan(s->previous);
  const bool counts = s->since_restart >= 0 && s->since_restart <= kMaxIterations && s->iterations >= 0 &&
                      s->iterations <= kMaxIterations && s->window_left >= -kMaxIterations &&
                      s->window_left <= kMaxIterations && s->restarts >= 0;
  const auto finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double e) { return std::isfinite(e); });
  };
  const bool values = finite(s->x) && finite(s->x0) && finite(s->y) && finite(s->y0) && finite(s->window_y);
  if (!sizes || !scalars || !counts || !values)
    throw IoError(path + ": not a shapematch checkpoint (an LP state after " + std::to_string(s->iterations) +
                  " iterations)");
  return s;
}

// A flag, then (where set) the attempt (version >= 2).
void write_attempt(Writer& w, const LevelAttempt& a, uint32_t version) {
  w(!a.empty());
  if (a.empty()) return;
  w(a.ring), w(a.local), w(a.propagated), w(a.priced), w(a.regional_done), w(a.around_done);
  w(a.suspicions), w(a.trusted);
  if (version >= 9) w(a.zero_cost_margin_given);
  if (version >= 11) w(a.suspicion_margins);
  if (version >= 17) w.array(a.proof_faces), w(a.proof_rings);
  if (version >= 20) w(a.proof_rows), w(a.proof_cols);
  each_field(a.report, w, version);
  w.array(a.extra);
  if (version < 3) return;
  const LevelAttempt::Rounding& g = a.rounding;
  w(g.rounds);
  if (!g.empty()) {
    w(g.columns), w(g.rows), w(g.iterations), w(g.lower_bound), w(g.reference_seconds), w(g.reference_iterations);
    w.array(g.ones);
    if (version >= 10) w.array(g.steps);
    if (version >= 12) w(g.cap_scale);
    if (version >= 14) {
      w(!g.warm.empty());
      if (!g.warm.empty()) write_iterate(w, g.warm);
    }
  }
  if (version < 13) return;
  w(!a.priced_from.empty());
  if (!a.priced_from.empty()) write_iterate(w, a.priced_from);
  w(!a.solving.empty());
  if (!a.solving.empty()) {
    write_iterate(w, a.solving);
    w(a.solving_iterations);
    if (version >= 14) w(a.solving_seconds);
    w(a.solving_resolve);
    if (version >= 14) w(a.solving_watched);
    if (version >= 16) write_watch(w, a.solving_watch);
    if (version >= 19) {
      w(a.solving_state != nullptr);
      if (a.solving_state) write_state(w, *a.solving_state);
    }
  }
  if (!a.priced_from.empty() || !a.solving.empty()) w(a.cold_iterations), w(a.cold_seconds);
}
void read_attempt(Reader& r, LevelAttempt& a, uint32_t version, const std::string& path) {
  bool held = false;
  r(held);
  if (!held) return;
  r(a.ring), r(a.local), r(a.propagated), r(a.priced), r(a.regional_done), r(a.around_done);
  r(a.suspicions), r(a.trusted);
  if (version >= 9) r(a.zero_cost_margin_given);
  if (version >= 11) r(a.suspicion_margins);
  if (version >= 17) r.array(a.proof_faces), r(a.proof_rings);
  if (version >= 20) r(a.proof_rows), r(a.proof_cols);
  each_field(a.report, r, version);
  r.array(a.extra);
  LevelAttempt::Rounding& g = a.rounding;
  if (version >= 3) r(g.rounds);
  if (g.rounds < 0) throw IoError(path + ": not a shapematch checkpoint (" + std::to_string(g.rounds) + " rounds)");
  if (!g.empty()) {
    r(g.columns), r(g.rows), r(g.iterations), r(g.lower_bound), r(g.reference_seconds), r(g.reference_iterations);
    r.array(g.ones);
    if (version >= 10) r.array(g.steps);
    if (version >= 12) r(g.cap_scale);
    bool warm = false;
    if (version >= 14) r(warm);
    if (warm) g.warm = read_iterate(r, path);
    if (!(g.cap_scale >= 1.0) || !std::isfinite(g.cap_scale))
      throw IoError(path + ": not a shapematch checkpoint (a rounding's cap scale of " + std::to_string(g.cap_scale) +
                    ")");
  }
  if (a.ring < 0) throw IoError(path + ": not a shapematch checkpoint (an attempt at ring " + std::to_string(a.ring) + ")");
  // (A local proof grows at most local_proof_depth rings: 8 by default.)
  if (a.proof_rings < 0 || a.proof_rings > kMaxProofRings)
    throw IoError(path + ": not a shapematch checkpoint (a local proof's region " + std::to_string(a.proof_rings) +
                  " rings out)");
  if (std::any_of(a.proof_faces.begin(), a.proof_faces.end(), [](int f) { return f < 0; }))
    throw IoError(path + ": not a shapematch checkpoint (a local proof's region on a negative face)");
  if (a.proof_rows < -1 || a.proof_cols < -1 || (a.proof_rows < 0) != (a.proof_cols < 0) ||
      (a.proof_rows >= 0 && a.proof_faces.empty()))
    throw IoError(path + ": not a shapematch checkpoint (a local proof's region of " + std::to_string(a.proof_rows) +
                  " rows and " + std::to_string(a.proof_cols) + " columns)");
  if (version < 13) return;
  bool priced = false, solving = false;
  r(priced);
  if (priced) a.priced_from = read_iterate(r, path);
  r(solving);
  if (solving) {
    a.solving = read_iterate(r, path);
    r(a.solving_iterations);
    if (version >= 14) r(a.solving_seconds);
    r(a.solving_resolve);
    if (version >= 14) r(a.solving_watched);
    if (version >= 16) a.solving_watch = read_watch(r, path);
    bool state = false;
    if (version >= 19) r(state);
    if (state) a.solving_state = read_state(r, path);
    if (a.solving_iterations < 0 || a.solving_iterations > kMaxIterations || !(a.solving_seconds >= 0.0) ||
        !std::isfinite(a.solving_seconds))
      throw IoError(path + ": not a shapematch checkpoint (an LP under way at " + std::to_string(a.solving_iterations) +
                    " iterations)");
  }
  if (priced || solving) r(a.cold_iterations), r(a.cold_seconds);
  if (a.cold_iterations < 0 || a.cold_iterations > kMaxIterations)
    throw IoError(path + ": not a shapematch checkpoint (a cold solve of " + std::to_string(a.cold_iterations) +
                  " iterations)");
  // (A re-solve is capped at the cold solve's iterations: it needs them.)
  if ((priced || a.solving_resolve) &&
      (a.cold_iterations <= 0 || !(a.cold_seconds >= 0.0) || !std::isfinite(a.cold_seconds)))
    throw IoError(path + ": not a shapematch checkpoint (a re-solve's cap of " + std::to_string(a.cold_iterations) +
                  " iterations)");
}

}  // namespace

void save_checkpoint(const std::string& path, const LevelCheckpoint& c) { detail::save_checkpoint_as(path, c, kVersion); }

void detail::save_checkpoint_as(const std::string& path, const LevelCheckpoint& c, uint32_t version) {
  if (version < 1 || version > kVersion) throw InvalidInputError("checkpoint version " + std::to_string(version));
  write_file_atomic(path, [&](std::ostream& out) {
    Writer w(out);
    w.put(kMagic, sizeof kMagic - 1);
    w(version);
    w(c.hierarchy);
    w(uint64_t(c.levels.size()));
    write_levels(w, c.levels, version);
    w.array(c.widened);
    if (version < 2) return;
    write_attempt(w, c.attempt, version);
    if (version < 5) return;
    w(uint64_t(c.chains.size()));
    for (const LevelCheckpoint::Chain& chain : c.chains) {
      w(chain.leading);
      w(uint64_t(chain.pending.size()));
      write_levels(w, chain.pending, version);
      w.array(chain.widened);
      if (version >= 6) write_attempt(w, chain.attempt, version);
    }
    if (version >= kFirstChecksummed) w.seal();
  });
}

LevelCheckpoint load_checkpoint(const std::string& path) {
  std::ifstream in = open_for_reading(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError(path + ": cannot read the checkpoint");
  if (bytes.compare(0, sizeof kMagic - 1, kMagic) != 0) throw IoError(path + ": not a shapematch checkpoint");
  // The checksum first: a damaged file is one line saying so, not whichever field it garbled.
  uint32_t stated = 0;
  if (bytes.size() >= sizeof kMagic - 1 + sizeof stated)
    std::memcpy(&stated, bytes.data() + sizeof kMagic - 1, sizeof stated);
  const std::string damaged = path + ": the checkpoint is damaged (its checksum does not match: changed or cut short "
                                     "since it was written)";
  // The checksum of the file's bytes before its last 8, its version field read as `version`.
  const size_t head = sizeof kMagic - 1 + sizeof stated;
  const bool summed = bytes.size() >= head + sizeof(uint64_t);
  uint64_t sum = 0;
  if (summed) std::memcpy(&sum, bytes.data() + bytes.size() - sizeof sum, sizeof sum);
  const auto sum_as = [&](uint32_t version) {
    Checksum c;
    c.add(bytes.data(), sizeof kMagic - 1);
    c.add(reinterpret_cast<const char*>(&version), sizeof version);
    c.add(bytes.data() + head, bytes.size() - sizeof sum - head);
    return c.value();
  };
  if (stated >= kFirstChecksummed && stated <= kVersion) {
    if (!summed) throw IoError(path + ": the checkpoint is cut short");
    if (sum_as(stated) != sum) throw IoError(damaged);
    bytes.resize(bytes.size() - sizeof sum);
  } else if (summed) {
    // A file of version 18 on whose version field alone changed: the rest matches under its own
    // version. (A file without a checksum ends so by chance 1 in 2^64; a later version's own file
    // matches none of these and is refused below.)
    for (uint32_t v = kFirstChecksummed; v <= kVersion; ++v)
      if (sum_as(v) == sum) throw IoError(damaged);
  }
  Reader r(path, std::move(bytes));
  std::string magic(sizeof kMagic - 1, '\0');
  r.take(magic.data(), magic.size());
  uint32_t version = 0;
  r(version);
  if (version < 1 || version > kVersion)
    throw IoError(path + ": checkpoint version " + std::to_string(version) + ", this build reads 1 to " +
                  std::to_string(kVersion));
  LevelCheckpoint c;
  r(c.hierarchy);
  uint64_t n = 0;
  r(n);
  if (n == 0 || n > 64) throw IoError(path + ": the checkpoint claims " + std::to_string(n) + " levels");
  read_levels(r, c.levels, n, version);
  r.array(c.widened);
  if (version >= 2) read_attempt(r, c.attempt, version, path);
  if (version >= 5) {
    uint64_t chains = 0;
    r(chains);
    if (chains != 0 && chains != 2)
      throw IoError(path + ": the checkpoint claims " + std::to_string(chains) + " lookahead chains");
    c.chains.resize(chains);
    for (LevelCheckpoint::Chain& chain : c.chains) {
      r(chain.leading);
      uint64_t k = 0;
      r(k);
      if (k == 0 || n + k > 64)  // (n: the levels before the split)
        throw IoError(path + ": a lookahead chain claims " + std::to_string(k) + " levels");
      read_levels(r, chain.pending, k, version);
      r.array(chain.widened);
      if (version >= 6) read_attempt(r, chain.attempt, version, path);
    }
  }
  if (!r.done()) throw IoError(path + ": trailing bytes after the checkpoint");
  return c;
}

}  // namespace shapematch
