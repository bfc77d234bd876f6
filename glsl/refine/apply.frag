// Guided refinement, last pass, at full resolution: the box means of (a, b), taken
// bilinearly from the low grid (four texelFetch, clamped at the edges: no float filtering
// needed, which many Mali GPUs lack), applied to the full-resolution colour guide: range =
// exp(ā·I + b̄).

uniform sampler2D u_colour;
uniform sampler2D u_coefficients;   // box means of (a_r, a_g, a_b, b) on the low grid
uniform ivec2 u_low_size;
uniform vec2 u_scale;               // low-grid texels per full-resolution pixel (x, y)
uniform bool u_colour_srgb;

out vec4 o_range;

// As pack.frag's: sRGB-encoded, less 0.5.
vec3 guide_at(ivec2 q) {
    vec3 c = texelFetch(u_colour, q, 0).rgb;
    c = u_colour_srgb ? clamp(c, 0.0, 1.0) : linear_to_srgb(c);
    return c - 0.5;
}

vec4 coefficients_at(ivec2 q) {
    return texelFetch(u_coefficients, clamp(q, ivec2(0), u_low_size - 1), 0);
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    // The pixel's centre in low-grid coordinates, texel centres at integers.
    vec2 c = (vec2(p) + 0.5) * u_scale - 0.5;
    vec2 f = floor(c);
    vec2 t = c - f;
    ivec2 q = ivec2(f);
    vec4 ab = mix(
        mix(coefficients_at(q), coefficients_at(q + ivec2(1, 0)), t.x),
        mix(coefficients_at(q + ivec2(0, 1)), coefficients_at(q + ivec2(1, 1)), t.x),
        t.y);
    o_range = vec4(exp(dot(ab.xyz, guide_at(p)) + ab.w), 0.0, 0.0, 1.0);
}
