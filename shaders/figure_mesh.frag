#version 430 core
// Tree figure: Lambert shading of a light grey, opaque mesh under one fixed light, plus an
// ambient term so that faces turned away from the light stay readable.
in vec3 v_normal;

uniform vec3 u_light;   // unit, world coordinates, pointing towards the light
uniform vec3 u_albedo;

out vec4 o_color;

void main() {
  float lambert = max(dot(normalize(v_normal), u_light), 0.0);
  o_color = vec4(u_albedo * (0.38 + 0.62 * lambert), 1.0);
}
