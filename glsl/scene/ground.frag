// The ground plane (y = 0): grass with patches of earth and a checker of 2 m and 10 m
// squares (so that a blur shows), and the lake, where the ground is water: a few sine
// waves moving with u_time, reflecting the sky by Fresnel. Every pattern is filtered by
// the pixel's footprint, so that it fades to its mean far away instead of aliasing.

uniform vec3 u_eye;
uniform float u_time;
uniform vec2 u_lake_centre;
uniform vec2 u_lake_radii;

in vec3 v_world;
in vec3 v_normal;
in vec4 v_colour;

out vec4 frag_colour;

// Negative in the lake: the formula of brume::scene::Lake::shore.
float lake_shore(vec2 p) {
    vec2 q = (p - u_lake_centre) / u_lake_radii;
    float a = (q.x == 0.0 && q.y == 0.0) ? 0.0 : atan(q.y, q.x);
    return length(q) - 1.0 - 0.06 * sin(5.0 * a + 0.7) - 0.03 * sin(11.0 * a + 2.1);
}

// A hash of an integer lattice point to [0, 1).
float hash(ivec2 c) {
    uint h = (uint(c.x) * 0x8DA6B343u) ^ (uint(c.y) * 0xD8163841u);
    h = (h ^ (h >> 13)) * 0x2C1B3C6Du;
    return float(h >> 8) / 16777216.0;
}

// Value noise in [0, 1] with a cell of 1.
float value_noise(vec2 p) {
    vec2 i = floor(p);
    vec2 f = p - i;
    vec2 u = f * f * (3.0 - 2.0 * f);
    ivec2 c = ivec2(i);
    float a = hash(c);
    float b = hash(c + ivec2(1, 0));
    float d = hash(c + ivec2(0, 1));
    float e = hash(c + ivec2(1, 1));
    return mix(mix(a, b, u.x), mix(d, e, u.x), u.y);
}

// 1 for a pattern of period `scale` much larger than the pixel's footprint, 0 when the
// footprint covers it.
float visible(float footprint, float scale) {
    return 1.0 - smoothstep(0.2 * scale, scale, footprint);
}

// Value noise of cell `scale`, faded to its mean (0.5) where it would alias.
float noise(vec2 p, float scale, float footprint) {
    float v = visible(footprint, scale);
    return v > 0.0 ? 0.5 + (value_noise(p / scale) - 0.5) * v : 0.5;
}

// A checker of squares of side `side` (0 or 1), box-filtered over the pixel's footprint
// (Quílez's analytic filter): 0.5 where the squares are smaller than a pixel.
float checker(vec2 p, float side) {
    vec2 q = p / side;
    vec2 w = max(abs(dFdx(q)), abs(dFdy(q))) + 1e-4;
    vec2 i = 2.0 * (abs(fract((q - 0.5 * w) * 0.5) - 0.5) - abs(fract((q + 0.5 * w) * 0.5) - 0.5)) / w;
    return 0.5 - 0.5 * i.x * i.y;
}

vec3 land(vec2 p, float footprint, float shore) {
    vec3 grass = mix(vec3(0.045, 0.085, 0.020), vec3(0.090, 0.120, 0.032), noise(p, 9.0, footprint));
    float earth = smoothstep(0.66, 0.85, noise(p + vec2(-211.0, 373.0), 45.0, footprint));
    vec3 albedo = mix(grass, vec3(0.12, 0.085, 0.05), 0.7 * earth);
    albedo *= mix(0.85, 1.15, checker(p, 2.0)) * mix(0.90, 1.10, checker(p + 1.0, 10.0));
    albedo = mix(albedo, vec3(0.32, 0.27, 0.18), 1.0 - smoothstep(0.0, 0.04, shore));
    return shade(albedo, vec3(0.0, 1.0, 0.0), 1.0);
}

vec3 water(vec2 p, float footprint, float shore) {
    // Slopes of sum a·sin(k·p + ω·t): wavelength, direction, amplitude per wave.
    const vec4 WAVES[4] = vec4[4](
        vec4(6.0, 0.80, 0.60, 0.070),
        vec4(3.7, -0.45, 0.89, 0.040),
        vec4(2.1, 0.96, -0.28, 0.022),
        vec4(1.3, -0.70, -0.71, 0.012));
    float t = u_time;
    vec2 slope = vec2(0.0);
    for (int i = 0; i < 4; i++) {
        float k = 6.2831853 / WAVES[i].x;
        float omega = sqrt(9.81 * k);
        vec2 dir = WAVES[i].yz;
        float a = WAVES[i].w * visible(footprint, WAVES[i].x);
        slope += dir * (a * k * cos(k * dot(dir, p) + omega * t));
    }
    vec3 n = normalize(vec3(-slope.x, 1.0, -slope.y));
    vec3 v = normalize(v_world - u_eye);
    vec3 r = reflect(v, n);
    r.y = abs(r.y);
    float cos_theta = max(dot(-v, n), 0.0);
    float fresnel = 0.02 + 0.98 * pow(1.0 - cos_theta, 5.0);
    vec3 deep = mix(vec3(0.012, 0.030, 0.040), vec3(0.05, 0.07, 0.06), smoothstep(-0.08, 0.0, shore));
    vec3 glint = SUN_DISC * 0.02 * pow(max(dot(r, u_sun_direction), 0.0), 400.0);
    return mix(deep, sky_radiance(r) + glint, fresnel);
}

void main() {
    vec2 p = v_world.xz;
    float footprint = max(length(dFdx(p)), length(dFdy(p)));
    float shore = lake_shore(p);
    float wet = clamp(0.5 - shore / max(fwidth(shore), 1e-6), 0.0, 1.0);
    vec3 colour = land(p, footprint, shore);
    if (wet > 0.0) {
        colour = mix(colour, water(p, footprint, shore), wet);
    }
    frag_colour = vec4(colour, 1.0);
}
