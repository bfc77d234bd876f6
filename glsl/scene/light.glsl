// The scene's light, put after the prelude in the fragment shaders that shade (objects,
// ground, sky): the sun, the sky's radiance by direction and the Lambert + ambient
// shading of a diffuse surface. Linear RGB, an exposure where a white wall facing the sun
// is about 1.

// Unit vector toward the sun (world, y up).
uniform vec3 u_sun_direction;

// Irradiance of the sun on a surface facing it, and radiance of its disc.
const vec3 SUN_IRRADIANCE = vec3(1.50, 1.38, 1.20);
const vec3 SUN_DISC = vec3(40.0, 36.0, 30.0);
// Angular radius of the disc (rad): 0.6°, larger than the real sun (0.27°) so it shows.
const float SUN_RADIUS = 0.0105;

const vec3 SKY_ZENITH = vec3(0.10, 0.22, 0.56);
const vec3 SKY_HORIZON = vec3(0.62, 0.72, 0.86);
// Below the horizon, seen only past the end of the ground (beyond the far plane).
const vec3 SKY_BELOW = vec3(0.45, 0.50, 0.55);

// Sky radiance along the unit direction `dir`, without the sun's disc: a gradient from a
// bright horizon to a deep blue zenith, and a glow around the sun.
vec3 sky_radiance(vec3 dir) {
    float h = dir.y;
    vec3 sky = h >= 0.0 ? mix(SKY_HORIZON, SKY_ZENITH, sqrt(h))
                        : mix(SKY_HORIZON, SKY_BELOW, clamp(-h * 8.0, 0.0, 1.0));
    float toward_sun = max(dot(dir, u_sun_direction), 0.0);
    float t2 = toward_sun * toward_sun;
    float t8 = t2 * t2 * t2 * t2;
    sky += vec3(0.90, 0.70, 0.45) * (0.25 * t8 + 0.6 * exp(200.0 * (toward_sun - 1.0)));
    return sky;
}

// The sun's disc along `dir`, with a soft edge of a tenth of its radius (cosines of the
// angles, for the small angles of the disc: 1 − θ²/2).
vec3 sun_disc(vec3 dir) {
    const float INNER = 1.0 - 0.5 * (0.9 * SUN_RADIUS) * (0.9 * SUN_RADIUS);
    const float OUTER = 1.0 - 0.5 * SUN_RADIUS * SUN_RADIUS;
    return SUN_DISC * smoothstep(OUTER, INNER, dot(dir, u_sun_direction));
}

// Light reflected by a diffuse surface of linear `albedo` and unit normal `n`: the sun
// (Lambert, no shadows) plus a hemisphere of sky above and ground light below, times
// `occlusion` for the ambient part.
vec3 shade(vec3 albedo, vec3 n, float occlusion) {
    float sun = max(dot(n, u_sun_direction), 0.0);
    vec3 ambient = mix(vec3(0.07, 0.08, 0.05), vec3(0.30, 0.38, 0.52), 0.5 + 0.5 * n.y);
    return albedo * (SUN_IRRADIANCE * sun + ambient * occlusion);
}
