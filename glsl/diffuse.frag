// Passes 2..N+1 (paper 000, eq. 11-12): one explicit diffusion step with four neighbours
// at distance h_k(x), each read by one hardware-bilinear fetch:
//   F(x) += Σ_u ½(ρ(x+u) + ρ(x)) (F(x+u) − F(x)).
// The offset law h_k = g(a·e^(k·b)) is the scheme-agnostic form of src/schedule.rs
// (offset_from_law); keep the two identical.
precision highp float;
precision highp sampler2D;

uniform sampler2D u_f;        // F at step k (bilinear, clamp to edge)
uniform sampler2D u_rate;     // ρ in .r (bilinear, clamp to edge)
uniform sampler2D u_law;      // (a, b) in .rg (texelFetch)
uniform float u_step;         // k
uniform bool u_moment_offsets; // true: h = m⁻¹(t²), the bilinear second-moment inverse
uniform vec2 u_texel;         // 1 / texture size

out vec4 o_f;

float offset_for_moment(float m) {
    float i = floor(sqrt(m));
    return i + (m - i * i) / (2.0 * i + 1.0);
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
    vec2 law = texelFetch(u_law, p, 0).rg;
    float t = law.x * exp(u_step * law.y);
    float h = u_moment_offsets ? offset_for_moment(t * t) : t;
    vec2 uv = gl_FragCoord.xy * u_texel;
    vec2 dx = vec2(h * u_texel.x, 0.0);
    vec2 dy = vec2(0.0, h * u_texel.y);
    o_f = f + flux(uv + dx, f, rate) + flux(uv - dx, f, rate)
            + flux(uv + dy, f, rate) + flux(uv - dy, f, rate);
}
