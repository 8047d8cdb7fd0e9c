#version 450
// y = A x for a ±1 matrix in signed CSR (see core/include/shapematch/sparse.hpp): bit 31 of an
// entry marks -1, bits 0..30 are the column. One invocation per row; rows are summed in entry
// order, as the C++ reference does, so results agree bit for bit.
layout(local_size_x = 256) in;

layout(std430, set = 0, binding = 0) readonly buffer RowPtr { uint row_ptr[]; };
layout(std430, set = 0, binding = 1) readonly buffer Entry { uint entry[]; };
layout(std430, set = 0, binding = 2) readonly buffer X { float x[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Y { float y[]; };

layout(push_constant) uniform Push { uint rows; } pc;

void main() {
  // A grid wider than the per-dimension workgroup limit continues in y (vk::dispatch_grid).
  const uint row = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 256u;
  if (row >= pc.rows) return;
  float sum = 0.0;
  const uint end = row_ptr[row + 1u];
  for (uint k = row_ptr[row]; k < end; ++k) {
    const uint e = entry[k];
    const float v = x[e & 0x7fffffffu];
    sum += (e & 0x80000000u) != 0u ? -v : v;
  }
  y[row] = sum;
}
