#include "vk/spmv.hpp"

#include <string>

#include "shapematch/errors.hpp"
#include "spmv_signed_spv.hpp"

namespace shapematch::vk {

namespace {
struct Push {
  uint32_t rows;
};
}  // namespace

SignedSpmv::SignedSpmv(Context& context)
    : context_(context), pipeline_(context, spv::spmv_signed, 4, sizeof(Push)) {}

DescriptorSet SignedSpmv::bind(const Buffer& row_ptr, const Buffer& entry, const Buffer& x,
                               const Buffer& y) const {
  return pipeline_.bind({&row_ptr, &entry, &x, &y});
}

void SignedSpmv::record(Sequence& sequence, const DescriptorSet& set, uint32_t rows) const {
  sequence.dispatch(pipeline_, set, Push{rows}, context_.grid(rows, kLocalSize));
}

std::vector<float> SignedSpmv::operator()(const SignedCsr& a, std::span<const float> x) {
  if (a.rows < 0 || a.rows > UINT32_MAX - 1 || a.cols < 0 || a.cols > SignedCsr::kNegative ||
      a.row_ptr.size() != static_cast<size_t>(a.rows) + 1 || a.entry.size() != a.row_ptr.back())
    throw InvalidInputError("SignedSpmv: malformed signed CSR matrix (" + std::to_string(a.rows) +
                            " x " + std::to_string(a.cols) + ")");
  if (x.size() != static_cast<size_t>(a.cols))
    throw InvalidInputError("SignedSpmv: x has " + std::to_string(x.size()) + " entries, A has " +
                            std::to_string(a.cols) + " columns");
  Buffer row_ptr = context_.upload(std::span<const uint32_t>(a.row_ptr));
  Buffer entry = context_.upload(std::span<const uint32_t>(a.entry));
  Buffer xb = context_.upload(x);
  Buffer y = context_.storage_buffer(static_cast<uint64_t>(a.rows) * sizeof(float));
  const DescriptorSet set = bind(row_ptr, entry, xb, y);
  Sequence sequence(context_);
  record(sequence, set, static_cast<uint32_t>(a.rows));
  sequence.submit_and_wait();
  return context_.download<float>(y, static_cast<size_t>(a.rows));
}

}  // namespace shapematch::vk
