// Paper 001's 5 x 5 Gaussian (σ = 1 px, table 1). The table's weights are G(x, y) at
// integer offsets, g(x)·g(y) with g(x) = e^(−x²/2)/√(2π), and sum to 0.9818: a blurred
// pixel would lose 1.8 % of its light, so brume divides g by its sum 0.990866 (the 2D
// weights by 0.981815). GAUSS_WEIGHTS in src/pipeline/engine.rs holds the same numbers.
// Texels beyond the image repeat the edge (as CLAMP_TO_EDGE). `srgb` decodes 8-bit sRGB
// colour; callers pass a constant, so that the decode is compiled in or out. Included by fog.frag and
// gauss_blur.frag after the prelude.

const float GAUSS_1D[3] = float[3](0.40261995, 0.24420134, 0.05448868); // g / Σg

vec3 fetch_colour(sampler2D image, ivec2 p, bool srgb) {
    vec3 c = texelFetch(image, clamp(p, ivec2(0), brume_size - 1), 0).rgb;
    return srgb ? srgb_to_linear(c) : c;
}

vec3 gauss5(sampler2D image, ivec2 p, bool srgb) {
#if GAUSS_BILINEAR
    // The kernel is separable, and each side pair (g1 at 1, g2 at 2) is one bilinear
    // fetch of weight g1 + g2 at 1 + g2/(g1 + g2): 9 fetches instead of 25 (a quarter
    // less time on llvmpipe). The pipeline binds a LINEAR, CLAMP_TO_EDGE sampler object
    // for this pass, and chooses this path only for a filterable, linear colour texture.
    const float SIDE = GAUSS_1D[1] + GAUSS_1D[2];
    const float AT = 1.0 + GAUSS_1D[2] / SIDE;
    vec2 texel = 1.0 / vec2(brume_size);
    vec2 uv = (vec2(p) + 0.5) * texel;
    vec3 sum = vec3(0.0);
    for (int j = -1; j <= 1; ++j) {
        for (int i = -1; i <= 1; ++i) {
            float w = (i == 0 ? GAUSS_1D[0] : SIDE) * (j == 0 ? GAUSS_1D[0] : SIDE);
            vec2 at = uv + vec2(float(i), float(j)) * (AT * texel);
            sum += w * textureLod(image, at, 0.0).rgb;
        }
    }
    return sum;
#else
    vec3 sum = vec3(0.0);
    for (int j = -2; j <= 2; ++j) {
        for (int i = -2; i <= 2; ++i) {
            float w = GAUSS_1D[abs(i)] * GAUSS_1D[abs(j)];
            sum += w * fetch_colour(image, p + ivec2(i, j), srgb);
        }
    }
    return sum;
#endif
}

// How much of the blurred image a pixel takes (paper 001, sec. 3.4: the blur grows with
// the fog's density, with a distance, a falloff and a maximum):
//   b = min(max, density · (l / distance)^falloff),  density = 1 − mean τ.
uniform vec3 u_gauss; // (blur distance, falloff, maximum)

float blur_weight(MediumSample m, float depth) {
    float l = length(brume_ray) * brume_eye_depth(depth);
    float density = 1.0 - (m.transmission.r + m.transmission.g + m.transmission.b) / 3.0;
    return min(u_gauss.z, density * pow(max(l, 0.0) / u_gauss.x, u_gauss.y));
}
