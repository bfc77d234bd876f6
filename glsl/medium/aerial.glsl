// Paper 002's aerial perspective (src/medium/aerial.rs): per channel attenuation Γ_c(T, s)
// (eq. 11) read from a table over distance, the airlight of the view direction
// I∞(θ')·ζ(T, θ, θ') (eq. 12-13), θ the pixel's zenith angle from the camera's ray, and
// the blur from the scattering optical depth −ln Γ̄ (all of it scatters), capped at 10.
uniform sampler2D u_gamma;   // Γ_r, Γ_g, Γ_b over the table coordinate (RGB32F, 1 row)
uniform vec4 u_gamma_coord;  // (1/scale (1/m), 1/log span, largest distance (m), samples)
uniform float u_metres;      // metres per unit of the range texture
uniform vec3 u_horizon;      // I∞(θ'), linear RGB
uniform vec3 u_gradation;    // (A, B, 1/(1 + A·e^(B/cos θ'))) of eq. 13
uniform vec2 u_aerial_blur;  // (λ, 1 / the distance (m) that counts as 1 in the blur law)

const float AERIAL_MIN_COS = 0.0017453283; // cos(89.9°): eq. 13 diverges at the horizon
const float AERIAL_MAX_DEPTH = 10.0;       // τ = e^(−10): nothing left to blur
const float AERIAL_PI = 3.14159265358979;

#ifdef AERIAL_HORIZON_SECTORS
uniform sampler2D u_horizon_gain; // I∞'s gain by azimuth sector (RGB32F, 1 row)
uniform vec3 u_horizon_sectors;   // (centre azimuth (rad), 1 / sector width, sectors)

// The horizon light's gain toward `ray`: its azimuth (0 along −z, π/2 along +x) placed
// among the sectors, sector k's centre on texel k, linear between (HorizonSectors::gain).
vec3 aerial_horizon_gain(vec3 ray) {
    float d = atan(ray.x, -ray.z) - u_horizon_sectors.x;
    d = mod(d + AERIAL_PI, 2.0 * AERIAL_PI) - AERIAL_PI;
    float n = u_horizon_sectors.z;
    float u = (d * u_horizon_sectors.y + 0.5 * n) / n;
    return textureLod(u_horizon_gain, vec2(u, 0.5), 0.0).rgb;
}
#else
// One sector: its gain is in u_horizon already (AerialPerspective's uniforms), which
// spares each pixel an arc tangent and a lookup (about 6 % of this pass on llvmpipe).
vec3 aerial_horizon_gain(vec3 ray) {
    return vec3(1.0);
}
#endif

MediumSample medium_sample(ivec2 pixel, float depth) {
    float s = max(depth, 0.0) * u_metres;
    float x = log(1.0 + min(s, u_gamma_coord.z) * u_gamma_coord.x) * u_gamma_coord.y;
    float n = u_gamma_coord.w;
    float u = (0.5 + x * (n - 1.0)) / n;
    vec3 gamma = textureLod(u_gamma, vec2(u, 0.5), 0.0).rgb;
    float cos_theta = clamp(normalize(brume_ray).y, AERIAL_MIN_COS, 1.0);
    float zeta = (1.0 + u_gradation.x * exp(u_gradation.y / cos_theta)) * u_gradation.z;
    float mean = (gamma.r + gamma.g + gamma.b) / 3.0;
    float ds = min(-log(max(mean, 1e-30)), AERIAL_MAX_DEPTH);
    MediumSample m;
    m.transmission = gamma;
    m.inscatter = u_horizon * zeta * aerial_horizon_gain(brume_ray);
    m.sigma = brume_blur_scale(u_aerial_blur.x, s * u_aerial_blur.y, ds);
    return m;
}
