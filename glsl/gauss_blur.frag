// Paper 001's separate blur pass: the fogged image (fog.frag with WRITE_BLUR_WEIGHT, b in
// alpha) blurred by the 5 x 5 Gaussian and mixed with itself by b:
//   out = mix(F, gauss5(F), b).
// Assembled like fog.frag (the medium is compiled in for the declarations only).

uniform sampler2D u_f;     // fogged colour, b in alpha (brume's float target)
uniform ivec2 u_origin;    // corner of the output rectangle in the destination (px)
uniform int u_output_srgb; // 1: encode to sRGB

out vec4 o_colour;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy) - u_origin;
    vec4 f = texelFetch(u_f, p, 0);
    vec3 c = mix(f.rgb, gauss5(u_f, p, false), f.a);
    o_colour = vec4(u_output_srgb != 0 ? linear_to_srgb(c) : c, 1.0);
}
