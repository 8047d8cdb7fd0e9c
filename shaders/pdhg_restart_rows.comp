#version 450
// Restart over rows (core/src/pdhg_backend.hpp): y⁰ ← y ← ŷ and yr = r·ŷ, with per-workgroup
// partial sums of the anchor's displacement (ŷ − y⁰)².
#extension GL_EXT_buffer_reference : require
#extension GL_KHR_shader_subgroup_arithmetic : require
layout(local_size_x = 256) in;

layout(buffer_reference, std430, buffer_reference_align = 8) restrict buffer Doubles { double v[]; };

layout(push_constant) uniform Push {
  Doubles yhat, r, y, y0, yr, partial;
  uint m;
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

void main() {
  // A grid wider than the per-dimension workgroup limit continues in y (vk::dispatch_grid).
  const uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 256u;
  double change = 0.0lf;
  if (i < pc.m) {
    const double yh = pc.yhat.v[i];
    change = (yh - pc.y0.v[i]) * (yh - pc.y0.v[i]);
    pc.y.v[i] = yh;
    pc.y0.v[i] = yh;
    pc.yr.v[i] = pc.r.v[i] * yh;
  }
  const double s = workgroup_sum(change);
  if (gl_LocalInvocationIndex == 0u) pc.partial.v[gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x] = s;
}
