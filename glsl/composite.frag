// Pass N+2 (paper 000, eq. 4): out = F.rgb + (1 − τ_blurred)·L∞, with τ_blurred the
// diffused transmission (the alpha of F, and the second target of a chromatic medium),
// never the sharp τ; L∞ is the medium's in-scattered light at this pixel. In the offset
// layout (OFFSET_LAYOUT: L∞ the same everywhere, F = (τ·(E − L∞), ρ) diffused) the same
// image is L∞ + F.rgb.
// With the coarse stage (COARSE_BLEND) this pass is also its last blend: F is assembled
// from full-resolution F at step k0 and the half-resolution level (coarse_detail.glsl),
// which saves a full-resolution pass and its target's write and read.
// Assembled like medium.frag: #version, #defines, prelude.glsl, medium_api.glsl, the
// medium, coarse_detail.glsl with COARSE_BLEND, then this file.

uniform sampler2D u_f;      // diffused F (COARSE_BLEND: F at step k0)
#if CHROMATIC
uniform sampler2D u_tau_gb; // diffused (τ_g, τ_b)
#endif
uniform sampler2D u_depth;  // the host's depth or range texture, for the medium
uniform ivec2 u_origin;     // corner of the output rectangle in the destination (px)
uniform int u_output_srgb;  // 1: encode to sRGB (an 8-bit destination without sRGB format)

out vec4 o_colour;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy) - u_origin;
#if COARSE_BLEND
    vec4 f = coarse_blend(p, texelFetch(u_f, p, 0));
#else
    vec4 f = texelFetch(u_f, p, 0);
#endif
    vec3 inscatter = medium_sample(p, texelFetch(u_depth, p, 0).r).inscatter;
#if OFFSET_LAYOUT
    vec3 c = inscatter + f.rgb;
#else
#if CHROMATIC
    vec3 tau = vec3(f.a, texelFetch(u_tau_gb, p, 0).rg);
#else
    vec3 tau = vec3(f.a);
#endif
    vec3 c = f.rgb + (1.0 - tau) * inscatter;
#endif
    o_colour = vec4(u_output_srgb != 0 ? linear_to_srgb(c) : c, 1.0);
}
