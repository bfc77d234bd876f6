// Guided refinement, the box passes: the mean over a (2r + 1)-tap line, horizontal or
// vertical, of the four channels of each of LAYERS sources (4: the moments' textures, or
// 1: the windows' models), counting only taps inside the grid (He et al.'s normalisation
// by the box of ones: the borders are not darkened). After model.glsl (which defines
// WINDOW_MODEL), the vertical pass over the moments writes each window's model from the
// means instead of the means. Preceded by the #version line and #define LAYERS (a
// constant, not a uniform: llvmpipe ran a one-texture box 3x slower when the other three
// textures were only skipped at run time).

uniform sampler2D u_source0;
#if LAYERS > 1
uniform sampler2D u_source1;
uniform sampler2D u_source2;
uniform sampler2D u_source3;
#endif
uniform ivec2 u_size;
uniform ivec2 u_step;    // (1, 0) or (0, 1)
uniform int u_radius;

layout(location = 0) out vec4 o_mean0;
#if LAYERS > 1 && !defined(WINDOW_MODEL)
layout(location = 1) out vec4 o_mean1;
layout(location = 2) out vec4 o_mean2;
layout(location = 3) out vec4 o_mean3;
#endif

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 lo = max(p - u_radius * u_step, ivec2(0));
    ivec2 hi = min(p + u_radius * u_step, u_size - 1);
    int taps = (hi.x - lo.x) + (hi.y - lo.y) + 1;
    vec4 s0 = vec4(0.0);
#if LAYERS > 1
    vec4 s1 = vec4(0.0);
    vec4 s2 = vec4(0.0);
    vec4 s3 = vec4(0.0);
#endif
    for (int k = 0; k < taps; ++k) {
        ivec2 q = lo + k * u_step;
        s0 += texelFetch(u_source0, q, 0);
#if LAYERS > 1
        s1 += texelFetch(u_source1, q, 0);
        s2 += texelFetch(u_source2, q, 0);
        s3 += texelFetch(u_source3, q, 0);
#endif
    }
    float n = float(taps);
#if defined(WINDOW_MODEL)
    // The last box pass over the moments writes the windows' models, not their means.
    o_mean0 = window_model(s0 / n, s1 / n, s2 / n, s3.x / n);
#else
    o_mean0 = s0 / n;
#endif
#if LAYERS > 1 && !defined(WINDOW_MODEL)
    o_mean1 = s1 / n;
    o_mean2 = s2 / n;
    o_mean3 = s3 / n;
#endif
}
