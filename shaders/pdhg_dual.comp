#version 450
// PDHG dual step over rows i (core/src/pdhg_backend.hpp): gathers the extrapolated xr through A,
// then the Halpern update of y and yr = r·y, fused. Rows longer than long_row are left to
// pdhg_dual_long.comp. On the last iteration of a batch it also keeps
// ŷ, r·ŷ (for the evaluation) and per-workgroup partial sums of (ŷ − y)².
// Buffers are reached by device address, as in pdhg_primal.comp.
#extension GL_EXT_buffer_reference : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 256) in;

layout(buffer_reference, std430, buffer_reference_align = 4) restrict readonly buffer Words { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) restrict buffer Doubles { double v[]; };

layout(push_constant) uniform Push {
  Words a_ptr;        // A row offsets (m + 1)
  uint64_t a_entry;   // A entries: address of uint[nnz]
  Doubles xr, b, r, y, y0, yr, yhat, ys, partial;
  double sigma, gamma, w;  // doubles before the uints: the block stays within 128 bytes
  uint m, last, long_row;
} pc;

shared double sums[64];  // one per subgroup: subgroups of at least 4 invocations (checked on the host)

// Sum over the workgroup, in invocation 0; every invocation must reach it (it has a barrier).
// Subgroup sums first: lavapipe pays dearly per barrier, and this needs only one.
double workgroup_sum(double value) {
  const double s = subgroupAdd(value);
  if (subgroupElect()) sums[gl_SubgroupID] = s;
  barrier();
  double total = 0.0lf;
  if (gl_LocalInvocationIndex == 0u)
    for (uint k = 0u; k < gl_NumSubgroups; ++k) total += sums[k];
  return total;
}

// Σ_k ±v[col_k] over entries [begin, end), in entry order like the CPU backend.
double gather(uint64_t entry, uint begin, uint end, Doubles v) {
  Words e = Words(entry + uint64_t(begin) * 4ul);
  double s = 0.0lf;
  for (uint t = 0u; t < end - begin; ++t) {
    const uint k = e.v[t];
    const double f = v.v[k & 0x7fffffffu];
    s += (k & 0x80000000u) != 0u ? -f : f;
  }
  return s;
}

void main() {
  // A grid wider than the per-dimension workgroup limit continues in y (vk::dispatch_grid).
  const uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 256u;
  double change = 0.0lf;
  const uint begin = i < pc.m ? pc.a_ptr.v[i] : 0u;
  const uint end = i < pc.m ? pc.a_ptr.v[i + 1u] : 0u;
  if (i < pc.m && end - begin <= pc.long_row) {
    const double ri = pc.r.v[i];
    const double yi = pc.y.v[i];
    const double yh = yi + pc.sigma * (pc.b.v[i] - ri * gather(pc.a_entry, begin, end, pc.xr));
    const double y = pc.w * ((1.0lf + pc.gamma) * yh - pc.gamma * yi) + (1.0lf - pc.w) * pc.y0.v[i];
    pc.y.v[i] = y;
    pc.yr.v[i] = ri * y;
    if (pc.last != 0u) {
      pc.yhat.v[i] = yh;
      pc.ys.v[i] = ri * yh;
      change = (yh - yi) * (yh - yi);
    }
  }
  if (pc.last != 0u) {  // uniform: the whole workgroup reduces or none does
    const double s = workgroup_sum(change);
    if (gl_LocalInvocationIndex == 0u) pc.partial.v[gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x] = s;
  }
}
