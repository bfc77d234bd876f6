// The coarse stage's blend back to the finer level (src/pipeline/coarse.rs), shared by
// coarse_blend.frag (a coarse level into the next finer one) and composite.frag (the
// half-resolution level into full resolution, fused with the composite: COARSE_BLEND):
//   F_N(x) ≈ D_N↑(x) + a(x)·(F_k0(x) − D_k0↑(x))
// D↑ the coarse D up-sampled bilinearly. The detail that the 2x2 average took out of F at
// step k0 comes back, attenuated by a(x): the transfer of the blur that steps k0..N would
// have given it at the detail band's centre frequency, a quarter of a cycle per pixel of
// the finer level: a = exp(−2π²·(1/4)²·(σ_N² − σ_k0²)), σ_k² = σ0²·e^(2kρ(x)) (the matched
// scheme's variance after k steps). A pixel of rate 0 keeps its detail exactly (a = 1); a
// pixel blurred far past the pixel scale keeps none. In the offset layout (OFFSET_LAYOUT)
// ρ is the alpha of the finer level's D, and stays so in the result.

#if !OFFSET_LAYOUT
uniform sampler2D u_rate;    // the finer level's ρ
#endif
uniform sampler2D u_coarse;  // D after the last step (bilinear, clamp to edge)
uniform sampler2D u_coarse0; // D at step k0 (bilinear, clamp to edge)
uniform vec2 u_half_texel;   // 1 / the coarse level's size
uniform vec3 u_detail;       // (the band's decay·σ0², 2N, 2k0)

// F_N at texel p of the finer level, whose value at step k0 is `fine`.
vec4 coarse_blend(ivec2 p, vec4 fine) {
    // The finer texel centre p + ½ lies at (p + ½)/2 in coarse texels.
    vec2 uv = 0.5 * (vec2(p) + 0.5) * u_half_texel;
#if OFFSET_LAYOUT
    float rate = fine.a;
#else
    float rate = texelFetch(u_rate, p, 0).r;
#endif
    float a = exp(-u_detail.x * (exp(u_detail.y * rate) - exp(u_detail.z * rate)));
    vec4 coarse = textureLod(u_coarse, uv, 0.0);
    vec4 coarse0 = textureLod(u_coarse0, uv, 0.0);
    vec4 blended = coarse + a * (fine - coarse0);
#if OFFSET_LAYOUT
    blended.a = rate;
#endif
    return blended;
}
