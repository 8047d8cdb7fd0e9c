#version 450
// PDHG primal step over columns j (core/src/pdhg_backend.hpp): gathers yr through Aᵀ, then the
// clamp, the extrapolated point xr and the Halpern update of x, fused so that each vector is read
// and written once. On the last iteration of a batch it also keeps x̂, d·x̂ (for the evaluation)
// and per-workgroup partial sums of (x̂ − x)².
// Buffers are reached by device address (GL_EXT_buffer_reference), so no binding limits the size
// of A; an entry offset becomes a 64-bit address once per column.
#extension GL_EXT_buffer_reference : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 256) in;

layout(buffer_reference, std430, buffer_reference_align = 4) restrict readonly buffer Words { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) restrict buffer Doubles { double v[]; };

layout(push_constant) uniform Push {
  Words at_ptr;       // Aᵀ row offsets (n + 1)
  uint64_t at_entry; // Aᵀ entries: address of uint[nnz]
  Doubles yr, c, d, x, x0, xhat, xs, xr, partial;
  double tau, gamma, w;  // doubles before the uints: the block stays within 128 bytes
  uint n, last;
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
  const uint j = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 256u;
  double change = 0.0lf;
  if (j < pc.n) {
    const double dj = pc.d.v[j];
    const double g = pc.c.v[j] - dj * gather(pc.at_entry, pc.at_ptr.v[j], pc.at_ptr.v[j + 1u], pc.yr);
    const double xj = pc.x.v[j];
    const double xh = clamp(xj - pc.tau * g, 0.0lf, 1.0lf / dj);
    pc.xr.v[j] = dj * (2.0lf * xh - xj);
    pc.x.v[j] = pc.w * ((1.0lf + pc.gamma) * xh - pc.gamma * xj) + (1.0lf - pc.w) * pc.x0.v[j];
    if (pc.last != 0u) {
      pc.xhat.v[j] = xh;
      pc.xs.v[j] = dj * xh;
      change = (xh - xj) * (xh - xj);
    }
  }
  if (pc.last != 0u) {  // uniform: the whole workgroup reduces or none does
    const double s = workgroup_sum(change);
    if (gl_LocalInvocationIndex == 0u) pc.partial.v[gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x] = s;
  }
}
