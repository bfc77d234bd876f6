// Paper 003's post-process: one screen-aligned pass over the host's framebuffer, which
// already holds the scene; the shader outputs the fog colour and an alpha, and GL's
// fixed-function blending (SRC_ALPHA, ONE_MINUS_SRC_ALPHA) does
//   C = f·C_frag + (1 − f)·C_fog     (eq. 9, f = τ)
// The medium must be grey (one τ for the three channels).
// Assembled like fog.frag (without gauss5.glsl).

uniform sampler2D u_depth; // the host's depth texture (.r)
uniform ivec2 u_origin;    // corner of the output rectangle in the destination (px)

out vec4 o_colour;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy) - u_origin;
    MediumSample m = medium_sample(p, texelFetch(u_depth, p, 0).r);
    o_colour = vec4(m.inscatter, 1.0 - m.transmission.r);
}
