// The coarse stage's blend of a coarse level into the next finer coarse level (the blend
// into full resolution is fused with the composite: composite.frag, COARSE_BLEND).
// Preceded by the #version line, the #define OFFSET_LAYOUT, prelude.glsl and
// coarse_detail.glsl.

uniform sampler2D u_f; // the finer level's D at the coarse level's first step

layout(location = 0) out vec4 o_f;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    o_f = coarse_blend(p, texelFetch(u_f, p, 0));
}
