// Paper 001's separate blur pass: the fogged image (fog.frag with WRITE_BLUR_WEIGHT, b in
// alpha) blurred by the 5 x 5 Gaussian and mixed with itself by b:
//   out = mix(F, gauss5(F), b).
// Assembled like fog.frag (the medium is compiled in for the declarations only);
// OUTPUT_SRGB encodes for an 8-bit destination without an sRGB format.

uniform sampler2D u_f;     // fogged colour, b in alpha (brume's float target)
uniform ivec2 u_origin;    // corner of the output rectangle in the destination (px)

out vec4 o_colour;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy) - u_origin;
    vec4 f = texelFetch(u_f, p, 0);
    vec3 c = mix(f.rgb, gauss5(u_f, p, false), f.a);
#if OUTPUT_SRGB
    c = linear_to_srgb(c);
#endif
    o_colour = vec4(c, 1.0);
}
