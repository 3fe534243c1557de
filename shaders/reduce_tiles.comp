#version 430 core
// The GL cubemap estimator, pass 2: work group (box, slice) sums slice `slice` of the 6 m^2
// texels of the box's atlas tile (3m x 2m pixels), u_slice_texels of them in row order (the
// last slice may hold fewer), and writes one float; the host adds a box's u_slices floats in
// double. The slices keep each lane's loop to at most u_slice_texels / 256 trips: a driver may
// bound a shader's loop trips (llvmpipe ends every loop after 65,535 of them, silently).
layout(local_size_x = 256) in;

uniform sampler2D u_atlas;
uniform int u_m;
uniform int u_tiles_per_row;
uniform int u_slice_texels;
uniform int u_slices;

layout(std430, binding = 0) writeonly buffer Sums { float sums[]; };

shared float partial[256];

void main() {
  const int box = int(gl_WorkGroupID.x);
  const int slice = int(gl_WorkGroupID.y);
  const int lane = int(gl_LocalInvocationID.x);
  const int width = 3 * u_m;
  const ivec2 origin = ivec2(box % u_tiles_per_row, box / u_tiles_per_row) * ivec2(width, 2 * u_m);
  const int first = slice * u_slice_texels;
  const int end = min(6 * u_m * u_m, first + u_slice_texels);
  float acc = 0.0;
  for (int t = first + lane; t < end; t += 256) acc += texelFetch(u_atlas, origin + ivec2(t % width, t / width), 0).r;
  partial[lane] = acc;
  barrier();
  for (int stride = 128; stride > 0; stride >>= 1) {
    if (lane < stride) partial[lane] += partial[lane + stride];
    barrier();
  }
  if (lane == 0) sums[box * u_slices + slice] = partial[0];
}
