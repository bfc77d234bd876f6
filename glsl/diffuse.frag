// Passes 2..N+1 (paper 000, eq. 11-12): one explicit diffusion step with four neighbours
// at distance h_k(x), each read by one hardware-bilinear fetch:
//   F(x) += Σ_u ½(ρ(x+u) + ρ(x)) (F(x+u) − F(x)).
// The offset is a function of the pixel's rate and the step (OffsetLaw in src/schedule.rs;
// keep the two identical): t = scale·e^(c_k·ρ), and h = t, or h = m⁻¹(t²·sinh(ρ)/ρ) for the
// variance-matched scheme. VARIANCE_MATCHED, CHROMATIC and OFFSET_LAYOUT (0 or 1) are
// #defined by the pipeline: compile-time switches, because every uniform a fragment reads
// costs it a load per lane on llvmpipe. CHROMATIC diffuses a second target, (τ_g, τ_b),
// with the same weights (multiple render targets), for media whose transmission differs
// per channel (in the pre-multiplied layout only). OFFSET_LAYOUT: F = (τ·(E − L∞), ρ),
// whose alpha is the rate, constant over the steps: one fetch per neighbour reads its
// colour and its rate, four in all where the rate's own texture takes eight (a third
// less time per step on llvmpipe).
// Preceded by the #version line, the #defines and prelude.glsl.

uniform sampler2D u_f;    // F at step k (bilinear, clamp to edge)
#if !OFFSET_LAYOUT
uniform sampler2D u_rate; // ρ in .r (bilinear, clamp to edge)
#endif
uniform vec2 u_law;       // (scale, c_k) of the offset law at this step
uniform vec2 u_texel;     // 1 / texture size

layout(location = 0) out vec4 o_f;
#if CHROMATIC
uniform sampler2D u_tau_gb; // (τ_g, τ_b) at step k (bilinear, clamp to edge)
layout(location = 1) out vec2 o_tau_gb;
#endif

float offset_for_moment(float m) {
    float i = floor(sqrt(m));
    return i + (m - i * i) / (2.0 * i + 1.0);
}

// sinh(ρ)/ρ by its Taylor series to ρ⁶: exact to 5e-11 for ρ ≤ ¼, where the closed form
// (e^(2ρ) − 1)/(2ρ) would lose most of its digits to cancellation in f32.
float sinhc(float r) {
    float r2 = r * r;
    return 1.0 + r2 * (1.0 / 6.0 + r2 * (1.0 / 120.0 + r2 / 5040.0));
}

float offset_at(float rate) {
    float t = u_law.x * exp(u_law.y * rate);
#if VARIANCE_MATCHED
    return offset_for_moment(t * t * sinhc(rate));
#else
    return t;
#endif
}

// textureLod at level 0, not texture(): the textures have one level, and an implicit
// LOD costs derivatives and a log2 per quad (half the pass time on llvmpipe). It is still
// one hardware-bilinear fetch per neighbour.
#if !OFFSET_LAYOUT
float weight(vec2 uv, float rate) {
    return 0.5 * (textureLod(u_rate, uv, 0.0).r + rate);
}
#endif

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 f = texelFetch(u_f, p, 0);
#if OFFSET_LAYOUT
    float rate = f.a;
#else
    float rate = texelFetch(u_rate, p, 0).r;
#endif
    float h = offset_at(rate);
    vec2 uv = gl_FragCoord.xy * u_texel;
    vec2 dx = vec2(h * u_texel.x, 0.0);
    vec2 dy = vec2(0.0, h * u_texel.y);
    vec2 neighbours[4] = vec2[4](uv + dx, uv - dx, uv + dy, uv - dy);
    o_f = f;
#if CHROMATIC
    vec2 g = texelFetch(u_tau_gb, p, 0).rg;
    o_tau_gb = g;
#endif
    for (int i = 0; i < 4; i++) {
#if OFFSET_LAYOUT
        // The rate in alpha stays as it is: only the colour diffuses.
        vec4 n = textureLod(u_f, neighbours[i], 0.0);
        o_f.rgb += 0.5 * (n.a + rate) * (n.rgb - f.rgb);
#else
        float r = weight(neighbours[i], rate);
        o_f += r * (textureLod(u_f, neighbours[i], 0.0) - f);
#endif
#if CHROMATIC
        o_tau_gb += r * (textureLod(u_tau_gb, neighbours[i], 0.0).rg - g);
#endif
    }
}
