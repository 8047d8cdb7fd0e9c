// The Vulkan PDHG backend: the kernels of pdhg_backend.hpp as compute shaders (shaders/pdhg_*.comp).
// A batch of iterations is recorded into one command buffer and submitted once; only the
// per-workgroup partial sums come back to the host, which adds them in double.
//
// Every buffer is reached by its device address (pushed with the other kernel arguments) rather
// than through a descriptor: maxStorageBufferRange (128 MiB on lavapipe) would otherwise cap A's
// entry arrays at 33M entries, and splitting arrays over several bindings needs non-uniform
// descriptor indexing, which lavapipe lacks. An allocation may still span at most
// maxMemoryAllocationSize (2 GiB on lavapipe).
#include "pdhg_backend.hpp"
#include "shapematch/errors.hpp"
#include "vk/context.hpp"
#include "vk/pipeline.hpp"
#include "vk/sequence.hpp"

#include "pdhg_dual_long_spv.hpp"
#include "pdhg_dual_spv.hpp"
#include "pdhg_eval_cols_spv.hpp"
#include "pdhg_eval_rows_long_spv.hpp"
#include "pdhg_eval_rows_spv.hpp"
#include "pdhg_primal_spv.hpp"
#include "pdhg_restart_cols_spv.hpp"
#include "pdhg_restart_rows_spv.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace shapematch::detail {
namespace {

constexpr uint32_t kLocalSize = 256;  // local_size_x of every pdhg_*.comp

// Push-constant blocks, member for member as declared in the shaders (addresses are 8 bytes).
struct PrimalPush {
  uint64_t at_ptr, at_entry, yr, c, d, x, x0, xhat, xs, xr, partial;
  double tau, gamma, w;
  uint32_t n, last;
};
struct DualPush {
  uint64_t a_ptr, a_entry, xr, b, r, y, y0, yr, yhat, ys, partial;
  double sigma, gamma, w;
  uint32_t m, last, long_row;
};
struct DualLongPush {
  uint64_t a_ptr, a_entry, rows, xr, b, r, y, y0, yr, yhat, ys, partial;
  double sigma, gamma, w;
  uint32_t count, last;
};
struct EvalRowsPush {
  uint64_t a_ptr, a_entry, xs, b, r, yhat, residual_out, by_out;
  uint32_t m, long_row;
};
struct EvalRowsLongPush {
  uint64_t a_ptr, a_entry, rows, xs, b, r, residual_out;
  uint32_t count;
};
static_assert(sizeof(DualLongPush) <= 128, "the push-constant block every device offers");
struct EvalColsPush {
  uint64_t at_ptr, at_entry, ys, c, d, xhat, cx_out, negative_out;
  uint32_t n;
};
struct RestartColsPush {
  uint64_t xhat, x, x0, partial;
  uint32_t n;
};
struct RestartRowsPush {
  uint64_t yhat, r, y, y0, yr, partial;
  uint32_t m;
};

// The kernels compute in fp64, reach buffers by address and reduce with subgroup sums (their
// shared arrays hold one slot per subgroup of ≥ 4 invocations): one clear error where a device
// cannot, before any pipeline is made.
const vk::Context& capable(const vk::Context& context) {
  const vk::Limits& l = context.limits();
  if (!l.shader_float64 || !l.buffer_device_address || !l.subgroup_arithmetic || l.subgroup_size < 4)
    throw DeviceError("pdhg-vulkan: " + context.info().name + " lacks shaderFloat64, shaderInt64, "
                      "bufferDeviceAddress (Vulkan 1.2) or compute subgroup arithmetic on subgroups of "
                      "at least 4, which the PDHG kernels need; use pdhg-cpu");
  return context;
}

uint32_t groups_in(const std::array<uint32_t, 3>& grid) { return grid[0] * grid[1] * grid[2]; }

// Partial sums: one slot per reduced quantity, of one double per workgroup that adds to it
// (the long-row kernels' after the row kernels').
enum Slot { kDx2, kCx, kNegative, kDy2, kResidual, kBy, kSlots };

// The problem on the device: A and Aᵀ, A's long rows, the column vectors (xs = d·x̂ and xr are
// scratch), the row vectors (ys = r·ŷ is scratch) and the partial sums.
struct DeviceProblem {
  vk::Buffer a_ptr, a_entry, at_ptr, at_entry, long_rows;
  vk::Buffer c, d, x, x0, xhat, xs, xr;
  vk::Buffer b, r, y, y0, yr, yhat, ys;
  vk::Buffer partial;
};

class VulkanBackend final : public PdhgBackend {
public:
  explicit VulkanBackend(int device_index)
      : context_(device_index),
        primal_(capable(context_), spv::pdhg_primal, 0, sizeof(PrimalPush)),
        dual_(context_, spv::pdhg_dual, 0, sizeof(DualPush)),
        dual_long_(context_, spv::pdhg_dual_long, 0, sizeof(DualLongPush)),
        eval_rows_(context_, spv::pdhg_eval_rows, 0, sizeof(EvalRowsPush)),
        eval_rows_long_(context_, spv::pdhg_eval_rows_long, 0, sizeof(EvalRowsLongPush)),
        eval_cols_(context_, spv::pdhg_eval_cols, 0, sizeof(EvalColsPush)),
        restart_cols_(context_, spv::pdhg_restart_cols, 0, sizeof(RestartColsPush)),
        restart_rows_(context_, spv::pdhg_restart_rows, 0, sizeof(RestartRowsPush)) {}

  std::string device() const override { return "vulkan: " + context_.info().name; }

  void load(const ScaledLp& lp, const std::vector<double>& x, const std::vector<double>& y) override {
    load_state(lp, x, x, y, y);
  }

  void load_state(const ScaledLp& lp, const std::vector<double>& x, const std::vector<double>& x0,
                  const std::vector<double>& y, const std::vector<double>& y0) override {
    problem_.reset();  // a failed load leaves nothing loaded; frees the old problem's memory first
    const SignedCsr& a = *lp.a;
    const SignedCsr& at = *lp.at;
    n_ = a.cols;
    m_ = a.rows;
    // Indices are 31-bit in the entries (bit 31 is the sign) and in SPIR-V, which reads an
    // array index as signed.
    if (m_ >= int64_t{SignedCsr::kNegative} || n_ >= int64_t{SignedCsr::kNegative} || at.rows != n_ || at.cols != m_ ||
        a.row_ptr.size() != size_t(m_) + 1 || at.row_ptr.size() != size_t(n_) + 1 ||
        lp.c.size() != size_t(n_) || lp.col_scale.size() != size_t(n_) || x.size() != size_t(n_) ||
        x0.size() != size_t(n_) || lp.b.size() != size_t(m_) || lp.row_scale.size() != size_t(m_) ||
        y.size() != size_t(m_) || y0.size() != size_t(m_))
      throw InvalidInputError("pdhg-vulkan: inconsistent problem of " + std::to_string(m_) + " x " +
                              std::to_string(n_));
    std::vector<uint32_t> long_rows;
    for (int64_t i = 0; i < m_; ++i)
      if (a.row_ptr[i + 1] - a.row_ptr[i] > kLongRow) long_rows.push_back(uint32_t(i));
    long_count_ = uint32_t(long_rows.size());
    long_rows.push_back(0);  // never read; keeps the buffer non-empty
    col_grid_ = context_.grid(uint64_t(n_), kLocalSize);
    row_grid_ = context_.grid(uint64_t(m_), kLocalSize);
    long_grid_ = context_.grid(uint64_t(long_count_) * kLongLanes, kLongLanes);
    col_groups_ = groups_in(col_grid_);
    row_groups_ = groups_in(row_grid_);
    stride_ = std::max(col_groups_, row_groups_ + long_count_);
    check_memory(a, at);

    const auto u32 = [&](const std::vector<uint32_t>& v) {
      return context_.upload_addressed(std::span<const uint32_t>(v));
    };
    const auto f64 = [&](const std::vector<double>& v) {
      return context_.upload_addressed(std::span<const double>(v));
    };
    const auto scratch = [&](int64_t size) { return context_.addressed_buffer(uint64_t(size) * sizeof(double)); };
    std::vector<double> yr(m_);
    for (int64_t i = 0; i < m_; ++i) yr[i] = lp.row_scale[i] * y[i];  // (as the dual kernel makes it)
    // x̂, ŷ start at the start point, so that read() before any iteration returns it.
    // Braced initialisation runs in member order, so the first failed allocation stops the rest.
    problem_.emplace(DeviceProblem{u32(a.row_ptr), u32(a.entry), u32(at.row_ptr), u32(at.entry), u32(long_rows),
                                   f64(lp.c), f64(lp.col_scale), f64(x), f64(x0), f64(x), scratch(n_),
                                   scratch(n_), f64(lp.b), f64(lp.row_scale), f64(y), f64(y0), f64(yr),
                                   f64(y), scratch(m_), scratch(int64_t(kSlots) * stride_)});
    partials_.resize(size_t(kSlots) * stride_);
  }

  BatchStats iterate(int count, int64_t k0, const Step& step) override {
    const DeviceProblem& p = loaded("iterate");
    // Re-recorded per batch: the Halpern weights depend on k0, and recording is cheap.
    vk::Sequence sequence(context_);
    for (int it = 0; it < count; ++it) {
      const uint32_t last = it + 1 == count;
      const double kk = static_cast<double>(k0 + it);
      const double w = (kk + 1.0) / (kk + 2.0);
      sequence.dispatch(primal_,
                        PrimalPush{p.at_ptr.address(), p.at_entry.address(), p.yr.address(), p.c.address(),
                                   p.d.address(), p.x.address(), p.x0.address(), p.xhat.address(),
                                   p.xs.address(), p.xr.address(), slot(kDx2), step.tau, step.gamma, w,
                                   uint32_t(n_), last},
                        col_grid_);
      sequence.dispatch(dual_,
                        DualPush{p.a_ptr.address(), p.a_entry.address(), p.xr.address(), p.b.address(),
                                 p.r.address(), p.y.address(), p.y0.address(), p.yr.address(),
                                 p.yhat.address(), p.ys.address(), slot(kDy2), step.sigma, step.gamma, w,
                                 uint32_t(m_), last, kLongRow},
                        row_grid_);
      if (long_count_ > 0)
        sequence.dispatch(dual_long_,
                          DualLongPush{p.a_ptr.address(), p.a_entry.address(), p.long_rows.address(), p.xr.address(),
                                       p.b.address(), p.r.address(), p.y.address(), p.y0.address(), p.yr.address(),
                                       p.yhat.address(), p.ys.address(), slot(kDy2, row_groups_), step.sigma,
                                       step.gamma, w, long_count_, last},
                          long_grid_);
    }
    sequence.dispatch(eval_rows_,
                      EvalRowsPush{p.a_ptr.address(), p.a_entry.address(), p.xs.address(), p.b.address(),
                                   p.r.address(), p.yhat.address(), slot(kResidual), slot(kBy), uint32_t(m_),
                                   kLongRow},
                      row_grid_);
    if (long_count_ > 0)
      sequence.dispatch(eval_rows_long_,
                        EvalRowsLongPush{p.a_ptr.address(), p.a_entry.address(), p.long_rows.address(),
                                         p.xs.address(), p.b.address(), p.r.address(),
                                         slot(kResidual, row_groups_), long_count_},
                        long_grid_);
    sequence.dispatch(eval_cols_,
                      EvalColsPush{p.at_ptr.address(), p.at_entry.address(), p.ys.address(), p.c.address(),
                                   p.d.address(), p.xhat.address(), slot(kCx), slot(kNegative), uint32_t(n_)},
                      col_grid_);
    sequence.submit_and_wait();
    download_partials();
    BatchStats stats;
    stats.dx2 = sum(kDx2, col_groups_);
    stats.dy2 = sum(kDy2, row_groups_ + long_count_);
    stats.residual2 = sum(kResidual, row_groups_ + long_count_);
    stats.by = sum(kBy, row_groups_);
    stats.cx = sum(kCx, col_groups_);
    stats.reduced_neg = sum(kNegative, col_groups_);
    return stats;
  }

  std::pair<double, double> restart() override {
    const DeviceProblem& p = loaded("restart");
    vk::Sequence sequence(context_);
    sequence.dispatch(restart_cols_,
                      RestartColsPush{p.xhat.address(), p.x.address(), p.x0.address(), slot(kDx2), uint32_t(n_)},
                      col_grid_);
    sequence.dispatch(restart_rows_,
                      RestartRowsPush{p.yhat.address(), p.r.address(), p.y.address(), p.y0.address(),
                                      p.yr.address(), slot(kDy2), uint32_t(m_)},
                      row_grid_);
    sequence.submit_and_wait();
    download_partials();
    return {sum(kDx2, col_groups_), sum(kDy2, row_groups_)};
  }

  bool read_state(std::vector<double>& x, std::vector<double>& x0, std::vector<double>& y,
                  std::vector<double>& y0) override {
    const DeviceProblem& p = loaded("read_state");
    x = context_.download<double>(p.x, size_t(n_));
    x0 = context_.download<double>(p.x0, size_t(n_));
    y = context_.download<double>(p.y, size_t(m_));
    y0 = context_.download<double>(p.y0, size_t(m_));
    return true;
  }

  void read(std::vector<double>& xhat, std::vector<double>& yhat) override {
    const DeviceProblem& p = loaded("read");
    xhat = context_.download<double>(p.xhat, size_t(n_));
    yhat = context_.download<double>(p.yhat, size_t(m_));
  }

private:
  // One clear error before allocating a problem that cannot fit, rather than a failed
  // allocation halfway through the uploads.
  void check_memory(const SignedCsr& a, const SignedCsr& at) const {
    const uint64_t bytes = 4 * (a.row_ptr.size() + a.entry.size() + at.row_ptr.size() + at.entry.size()) +
                           4 * uint64_t(long_count_ + 1) +
                           8 * (7 * uint64_t(n_) + 7 * uint64_t(m_) + uint64_t(kSlots) * stride_);
    const uint64_t available = context_.limits().device_local_bytes;
    if (bytes > available)
      throw DeviceError("pdhg-vulkan: the problem (" + std::to_string(m_) + " x " + std::to_string(n_) + ", " +
                        std::to_string(a.entry.size()) + " nonzeros) needs " + std::to_string(bytes >> 20) +
                        " MiB of device memory; " + context_.info().name + " has " +
                        std::to_string(available >> 20) + " MiB");
  }

  const DeviceProblem& loaded(const char* call) const {
    if (!problem_) throw DeviceError(std::string("pdhg-vulkan: ") + call + "() before load()");
    return *problem_;
  }

  // Slot s, from its `first` workgroup on.
  uint64_t slot(Slot s, uint32_t first = 0) const {
    return problem_->partial.address() + (uint64_t(s) * stride_ + first) * sizeof(double);
  }

  void download_partials() {
    context_.download(problem_->partial, partials_.data(), partials_.size() * sizeof(double));
  }

  double sum(Slot s, uint32_t groups) const {
    const auto begin = partials_.begin() + ptrdiff_t(s) * stride_;
    return std::accumulate(begin, begin + groups, 0.0);
  }

  vk::Context context_;
  vk::ComputePipeline primal_, dual_, dual_long_, eval_rows_, eval_rows_long_, eval_cols_, restart_cols_, restart_rows_;
  std::optional<DeviceProblem> problem_;
  int64_t n_ = 0, m_ = 0;
  std::array<uint32_t, 3> col_grid_{}, row_grid_{}, long_grid_{};
  uint32_t col_groups_ = 0, row_groups_ = 0, long_count_ = 0;
  uint32_t stride_ = 0;  // doubles per slot of partial sums
  std::vector<double> partials_;
};

}  // namespace

std::unique_ptr<PdhgBackend> make_vulkan_backend(int device_index) {
  return std::make_unique<VulkanBackend>(device_index);
}

}  // namespace shapematch::detail
