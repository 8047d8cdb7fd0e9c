#version 450
// Batch statistics over the long rows of A (core/src/pdhg_backend.hpp), one workgroup per row
// in the long-row order of pdhg_dual_long.comp: ((A x)_i − b_i)² with x = d·x̂, one slot per
// workgroup. Their bᵀy terms stay with pdhg_eval_rows.comp.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;  // kLongLanes

layout(buffer_reference, std430, buffer_reference_align = 4) restrict readonly buffer Words { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) restrict buffer Doubles { double v[]; };

layout(push_constant) uniform Push {
  Words a_ptr;
  uint64_t a_entry;
  Words rows;
  Doubles xs, b, r, residual_out;
  uint count;
} pc;

shared double lanes[64];

void main() {
  const uint g = gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
  if (g >= pc.count) return;  // whole workgroups only: the barriers below stay uniform
  const uint l = gl_LocalInvocationID.x;
  const uint i = pc.rows.v[g];
  const uint begin = pc.a_ptr.v[i], n = pc.a_ptr.v[i + 1u] - begin;
  Words e = Words(pc.a_entry + uint64_t(begin) * 4ul);
  double s = 0.0lf;
  for (uint t = l; t < n; t += 64u) {
    const uint k = e.v[t];
    const double f = pc.xs.v[k & 0x7fffffffu];
    s += (k & 0x80000000u) != 0u ? -f : f;
  }
  lanes[l] = s;
  barrier();
  for (uint h = 32u; h > 0u; h >>= 1u) {
    if (l < h) lanes[l] = lanes[l] + lanes[l + h];
    barrier();
  }
  if (l == 0u) {
    const double residual = lanes[0] - pc.b.v[i] / pc.r.v[i];
    pc.residual_out.v[g] = residual * residual;
  }
}
