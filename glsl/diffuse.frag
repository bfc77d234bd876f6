// Passes 2..N+1 (paper 000, eq. 11-12): one explicit diffusion step with four neighbours
// at distance h_k(x), each read by one hardware-bilinear fetch:
//   F(x) += Σ_u ½(ρ(x+u) + ρ(x)) (F(x+u) − F(x)).
// The offset is a function of the pixel's rate and the step (OffsetLaw in src/schedule.rs;
// keep the two identical): t = scale·e^(c_k·ρ), and h = t, or h = m⁻¹(t²·sinh(ρ)/ρ) for the
// variance-matched scheme. VARIANCE_MATCHED (0 or 1) is #defined by the pipeline: a
// compile-time switch, because every uniform a fragment reads costs it a load per lane
// on llvmpipe.
precision highp float;
precision highp sampler2D;

uniform sampler2D u_f;    // F at step k (bilinear, clamp to edge)
uniform sampler2D u_rate; // ρ in .r (bilinear, clamp to edge)
uniform vec2 u_law;       // (scale, c_k) of the offset law at this step
uniform vec2 u_texel;     // 1 / texture size

out vec4 o_f;

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
vec4 flux(vec2 uv, vec4 f, float rate) {
    float r = 0.5 * (textureLod(u_rate, uv, 0.0).r + rate);
    return r * (textureLod(u_f, uv, 0.0) - f);
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 f = texelFetch(u_f, p, 0);
    float rate = texelFetch(u_rate, p, 0).r;
    float h = offset_at(rate);
    vec2 uv = gl_FragCoord.xy * u_texel;
    vec2 dx = vec2(h * u_texel.x, 0.0);
    vec2 dy = vec2(0.0, h * u_texel.y);
    o_f = f + flux(uv + dx, f, rate) + flux(uv - dx, f, rate)
            + flux(uv + dy, f, rate) + flux(uv - dy, f, rate);
}
