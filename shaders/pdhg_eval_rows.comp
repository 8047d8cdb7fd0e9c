#version 450
// Batch statistics over rows i, in original units (core/src/pdhg_backend.hpp): per-workgroup
// partial sums of ((A x)_i − b_i)² with x = d·x̂ (kept by the primal kernel), and of bᵀy = b̃ᵀŷ.
// The residuals of rows longer than long_row are pdhg_eval_rows_long.comp's.
#extension GL_EXT_buffer_reference : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 256) in;

layout(buffer_reference, std430, buffer_reference_align = 4) restrict readonly buffer Words { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) restrict buffer Doubles { double v[]; };

layout(push_constant) uniform Push {
  Words a_ptr;
  uint64_t a_entry;
  Doubles xs, b, r, yhat, residual_out, by_out;
  uint m, long_row;
} pc;

shared dvec2 sums[64];  // one per subgroup: subgroups of at least 4 invocations (checked on the host)

// Two sums over the workgroup, in invocation 0; every invocation must reach it (it has a barrier).
// Subgroup sums first: lavapipe pays dearly per barrier, and this needs only one.
dvec2 workgroup_sum(dvec2 value) {
  const dvec2 s = subgroupAdd(value);
  if (subgroupElect()) sums[gl_SubgroupID] = s;
  barrier();
  dvec2 total = dvec2(0.0lf);
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
  dvec2 terms = dvec2(0.0lf);
  if (i < pc.m) {
    const double bi = pc.b.v[i];
    const uint begin = pc.a_ptr.v[i], end = pc.a_ptr.v[i + 1u];
    const double residual = end - begin <= pc.long_row ? gather(pc.a_entry, begin, end, pc.xs) - bi / pc.r.v[i] : 0.0lf;
    terms = dvec2(residual * residual, bi * pc.yhat.v[i]);
  }
  const dvec2 s = workgroup_sum(terms);
  if (gl_LocalInvocationIndex == 0u) {
    const uint g = gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
    pc.residual_out.v[g] = s.x;
    pc.by_out.v[g] = s.y;
  }
}
