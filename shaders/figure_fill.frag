#version 430 core
// Tree figure: box faces and box edges alike write their colour unlit.
in vec4 v_color;

out vec4 o_color;

void main() { o_color = v_color; }
