// Engine fog in one pass (papers 001 and 003), no diffusion:
//   out = τ·C + (1 − τ)·L∞
// with τ and L∞ from the medium. GAUSS_SINGLE blurs the fog-free colour first, in the
// same pass (paper 001, "single pass"): C ← mix(C, gauss5(C), b). WRITE_BLUR_WEIGHT writes
// the fogged colour with b in alpha to a float target instead, for gauss_blur.frag
// (paper 001, "separate passes"). COLOUR_SRGB decodes an 8-bit sRGB colour texture,
// OUTPUT_SRGB encodes for an 8-bit destination without an sRGB format.
// Assembled by src/pipeline/engine.rs: #version, #defines, prelude.glsl, medium_api.glsl,
// the medium's glsl/medium/*.glsl, gauss5.glsl, then this file.

uniform sampler2D u_colour; // the host's colour texture
uniform sampler2D u_depth;  // the host's depth texture (.r)
uniform ivec2 u_origin;     // corner of the output rectangle in the destination (px)

out vec4 o_colour;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy) - u_origin;
    float depth = texelFetch(u_depth, p, 0).r;
    MediumSample m = medium_sample(p, depth);
    const bool srgb = COLOUR_SRGB != 0;
    vec3 c = fetch_colour(u_colour, p, srgb);
#if GAUSS_SINGLE
    c = mix(c, gauss5(u_colour, p, srgb), blur_weight(m, depth));
#endif
    vec3 fogged = m.transmission * c + (1.0 - m.transmission) * m.inscatter;
#if WRITE_BLUR_WEIGHT
    o_colour = vec4(fogged, blur_weight(m, depth));
#else
#if OUTPUT_SRGB
    fogged = linear_to_srgb(fogged);
#endif
    o_colour = vec4(fogged, 1.0);
#endif
}
