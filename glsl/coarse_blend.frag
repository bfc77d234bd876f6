// The coarse stage's last pass (src/pipeline/coarse.rs): back to full resolution,
//   F_N(x) ≈ D_N↑(x) + a(x)·(F_k0(x) − D_k0↑(x))
// D↑ the half-resolution D up-sampled bilinearly. The detail that the 2x2 average took out
// of F at step k0 comes back, attenuated by a(x): the transfer of the blur that steps k0..N
// would have given it at the detail band's centre frequency, a quarter of a cycle per
// pixel: a = exp(−2π²·(1/4)²·(σ_N² − σ_k0²)), σ_k² = σ0²·e^(2kρ(x)) (the matched scheme's
// variance after k steps). A pixel of rate 0 keeps its detail exactly (a = 1); a pixel
// blurred far past the pixel scale keeps none.
// Preceded by the #version line and prelude.glsl.

uniform sampler2D u_f;       // full-resolution F at step k0
uniform sampler2D u_rate;    // full-resolution ρ
uniform sampler2D u_coarse;  // D after the last step (bilinear, clamp to edge)
uniform sampler2D u_coarse0; // D at step k0 (bilinear, clamp to edge)
uniform vec2 u_half_texel;   // 1 / half-resolution size
uniform vec3 u_detail;       // (2π²/16·σ0², 2N, 2k0)

layout(location = 0) out vec4 o_f;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    // Full-resolution pixel centre x + ½ lies at (x + ½)/2 in half-resolution texels.
    vec2 uv = 0.5 * gl_FragCoord.xy * u_half_texel;
    float rate = texelFetch(u_rate, p, 0).r;
    float a = exp(-u_detail.x * (exp(u_detail.y * rate) - exp(u_detail.z * rate)));
    vec4 coarse = textureLod(u_coarse, uv, 0.0);
    vec4 coarse0 = textureLod(u_coarse0, uv, 0.0);
    o_f = coarse + a * (texelFetch(u_f, p, 0) - coarse0);
}
