#version 450
// PDHG dual step over the long rows of A (more than kLongRow entries, core/src/pdhg_backend.hpp):
// one workgroup per row. Lane l sums entries l, l + 64, … in order, the lanes are added
// pairwise (l += l + h for h = 32, …, 1), and lane 0 makes the update of pdhg_dual.comp.
// One invocation per projection row (thousands of gathers in a chain) set the pace of every
// iteration before; this is the order the CPU backend adds long rows in, too.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;  // kLongLanes

layout(buffer_reference, std430, buffer_reference_align = 4) restrict readonly buffer Words { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) restrict buffer Doubles { double v[]; };

layout(push_constant) uniform Push {
  Words a_ptr;        // A row offsets (m + 1)
  uint64_t a_entry;   // A entries: address of uint[nnz]
  Words rows;         // the long rows, one per workgroup
  Doubles xr, b, r, y, y0, yr, yhat, ys, partial;  // partial: one slot per workgroup
  double sigma, gamma, w;
  uint count, last;   // count: number of long rows
} pc;

shared double lanes[64];

void main() {
  // A grid wider than the per-dimension workgroup limit continues in y (vk::dispatch_grid).
  const uint g = gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
  if (g >= pc.count) return;  // whole workgroups only: the barriers below stay uniform
  const uint l = gl_LocalInvocationID.x;
  const uint i = pc.rows.v[g];
  const uint begin = pc.a_ptr.v[i], n = pc.a_ptr.v[i + 1u] - begin;
  Words e = Words(pc.a_entry + uint64_t(begin) * 4ul);
  double s = 0.0lf;
  for (uint t = l; t < n; t += 64u) {
    const uint k = e.v[t];
    const double f = pc.xr.v[k & 0x7fffffffu];
    s += (k & 0x80000000u) != 0u ? -f : f;
  }
  lanes[l] = s;
  barrier();
  for (uint h = 32u; h > 0u; h >>= 1u) {
    if (l < h) lanes[l] = lanes[l] + lanes[l + h];
    barrier();
  }
  if (l == 0u) {
    const double ri = pc.r.v[i];
    const double yi = pc.y.v[i];
    const double yh = yi + pc.sigma * (pc.b.v[i] - ri * lanes[0]);
    const double y = pc.w * ((1.0lf + pc.gamma) * yh - pc.gamma * yi) + (1.0lf - pc.w) * pc.y0.v[i];
    pc.y.v[i] = y;
    pc.yr.v[i] = ri * y;
    if (pc.last != 0u) {
      pc.yhat.v[i] = yh;
      pc.ys.v[i] = ri * yh;
      pc.partial.v[g] = (yh - yi) * (yh - yi);
    }
  }
}
