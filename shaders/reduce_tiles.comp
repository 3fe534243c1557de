#version 430 core
// The GL cubemap estimator, pass 2: one work group per box sums the 6 m^2 texels of the box's
// atlas tile (3m x 2m pixels) and writes one float, so one number per box is read back.
layout(local_size_x = 256) in;

uniform sampler2D u_atlas;
uniform int u_m;
uniform int u_tiles_per_row;

layout(std430, binding = 0) writeonly buffer Sums { float sums[]; };

shared float partial[256];

void main() {
  const int box = int(gl_WorkGroupID.x);
  const int lane = int(gl_LocalInvocationID.x);
  const int width = 3 * u_m;
  const ivec2 origin = ivec2(box % u_tiles_per_row, box / u_tiles_per_row) * ivec2(width, 2 * u_m);
  const int n = 6 * u_m * u_m;
  float acc = 0.0;
  for (int t = lane; t < n; t += 256) acc += texelFetch(u_atlas, origin + ivec2(t % width, t / width), 0).r;
  partial[lane] = acc;
  barrier();
  for (int stride = 128; stride > 0; stride >>= 1) {
    if (lane < stride) partial[lane] += partial[lane + stride];
    barrier();
  }
  if (lane == 0) sums[box] = partial[0];
}
