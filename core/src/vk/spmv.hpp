#pragma once
// The signed SpMV kernel (shaders/spmv_signed.comp): y = A x for a ±1 matrix in signed CSR.
#include <cstdint>
#include <span>
#include <vector>

#include "shapematch/sparse.hpp"
#include "vk/context.hpp"
#include "vk/pipeline.hpp"
#include "vk/sequence.hpp"

namespace shapematch::vk {

class SignedSpmv {
public:
  static constexpr uint32_t kLocalSize = 256;  // local_size_x of the shader

  explicit SignedSpmv(Context& context);

  // y = A x with everything on the host: uploads, runs once, downloads. x has a.cols entries.
  std::vector<float> operator()(const SignedCsr& a, std::span<const float> x);

  // For solvers keeping A and the vectors on the device: bind once, record many times.
  DescriptorSet bind(const Buffer& row_ptr, const Buffer& entry, const Buffer& x,
                     const Buffer& y) const;
  void record(Sequence& sequence, const DescriptorSet& set, uint32_t rows) const;

private:
  Context& context_;
  ComputePipeline pipeline_;
};

}  // namespace shapematch::vk
