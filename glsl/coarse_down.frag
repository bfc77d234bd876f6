// The coarse stage's first pass (src/pipeline/coarse.rs): F and ρ at step k0 averaged over
// 2x2 blocks into the half-resolution targets. One hardware-bilinear fetch at the shared
// corner of a block is the mean of its four texels (clamp to edge at an odd size's last
// row and column). Writes D (the half-resolution F that the coarse steps diffuse), a copy
// of it kept as D at k0 for the blend, and the half-resolution rate: in D's alpha in the
// offset layout (OFFSET_LAYOUT, #defined 0 or 1), where one fetch averages both.
// Preceded by the #version line, the #define and prelude.glsl.

uniform sampler2D u_f;    // full-resolution F at step k0 (bilinear, clamp to edge)
#if !OFFSET_LAYOUT
uniform sampler2D u_rate; // full-resolution ρ (bilinear, clamp to edge)
#endif
uniform vec2 u_texel;     // 1 / full-resolution size

layout(location = 0) out vec4 o_d;
layout(location = 1) out vec4 o_d0;
#if !OFFSET_LAYOUT
layout(location = 2) out float o_rate;
#endif

void main() {
    // Half-resolution pixel (i, j) covers full-resolution texels 2i, 2i + 1 (and rows
    // 2j, 2j + 1): their shared corner is at 2i + 1 = 2·gl_FragCoord.x.
    vec2 uv = 2.0 * gl_FragCoord.xy * u_texel;
    vec4 d = textureLod(u_f, uv, 0.0);
    o_d = d;
    o_d0 = d;
#if !OFFSET_LAYOUT
    o_rate = textureLod(u_rate, uv, 0.0).r;
#endif
}
