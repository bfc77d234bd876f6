// Pass 1 (paper 000, eq. 1-2): the medium gives τ and σ at each pixel; this pass writes
//   F = (τ·E, τ_r)   the pre-multiplied colour (τ_r = τ for a grey medium, as the paper)
//   ρ(σ)             the pixel's diffusion rate (eq. 13 for euler, eq. 18 otherwise; the
//                    same as Schedule::rate in src/schedule.rs)
//   (τ_g, τ_b)       a chromatic medium's other two transmissions (CHROMATIC only)
// or, in the offset layout (OFFSET_LAYOUT: L∞ the same at every pixel), one target
//   (τ·(E − L∞), ρ)  which the composite turns into the same image (src/pipeline/mod.rs)
// Assembled by src/pipeline/mod.rs as: #version, #defines (CHROMATIC, OFFSET_LAYOUT,
// RATE_LAW_LOG, RATE_HALF), prelude.glsl, medium_api.glsl, the medium's
// glsl/medium/*.glsl, then this file.

uniform sampler2D u_colour; // the host's colour texture
uniform sampler2D u_depth;  // the host's depth or range texture (.r)
uniform int u_colour_srgb;  // 1: the colour texture holds sRGB-encoded values
uniform vec2 u_schedule;    // (σmax, 1/N) of the schedule; 1/N = 0 when N = 0

layout(location = 0) out vec4 o_f;
#if !OFFSET_LAYOUT
layout(location = 1) out float o_rate;
#endif
#if CHROMATIC
layout(location = 2) out vec2 o_tau_gb;
#endif

float rate_for(float sigma) {
    float s = clamp(sigma, brume_sigma0, u_schedule.x);
#if RATE_LAW_LOG
    return log(s / brume_sigma0) * u_schedule.y;
#else
    return (s * s - brume_sigma0 * brume_sigma0) * (0.5 * u_schedule.y);
#endif
}

// Rounded to the nearest half float here when the rate target is R16F: render targets may
// convert by truncation (llvmpipe does), a texture upload rounds to nearest, and the
// half-float rate must not depend on which path wrote it.
float store_rate(float rate) {
#if RATE_HALF
    return unpackHalf2x16(packHalf2x16(vec2(rate, 0.0))).x;
#else
    return rate;
#endif
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 e = texelFetch(u_colour, p, 0).rgb;
    if (u_colour_srgb != 0) {
        e = srgb_to_linear(e);
    }
    MediumSample m = medium_sample(p, texelFetch(u_depth, p, 0).r);
#if OFFSET_LAYOUT
    o_f = vec4(m.transmission * (e - m.inscatter), store_rate(rate_for(m.sigma)));
#else
    o_f = vec4(m.transmission * e, m.transmission.r);
    o_rate = store_rate(rate_for(m.sigma));
#endif
#if CHROMATIC
    o_tau_gb = m.transmission.gb;
#endif
}
