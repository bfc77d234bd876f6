// Paper 003's layered fog (src/medium/layered.rs has the derivation; keep the two
// identical): τ = e^(−F), F = l·δ̄ with l the Euclidean distance to the fragment and δ̄ the
// mean of the height profile δ(y) over the heights the segment spans (eq. 6-8), the fog
// colour in-scattered (eq. 9), and the blur from the scattering optical depth.
uniform float u_profile;    // 0 exponential, 1 sine band, 2 linear ramp, 3 table (medium uniforms have no int)
uniform vec3 u_layer;       // (density, base, scale height) | (density, base, thickness)
                            // | (density, floor, top)
uniform vec3 u_fog_colour;  // C_fog, linear RGB
uniform float u_albedo;     // scattering / extinction
uniform float u_lambda;     // λ (px)
uniform float u_range_unit; // the distance that counts as normalised range 1

const float LAYERED_PI = 3.14159265358979;
const float LAYERED_SERIES_LIMIT = 1.0;     // SERIES_LIMIT
const float LAYERED_EXPONENT_CAP = 80.0;    // EXPONENT_CAP: e^88 overflows f32
const float LAYERED_MAX_BLUR_DEPTH = 10.0;  // MAX_BLUR_OPTICAL_DEPTH

// sinh(h)/h and sin(h)/h for 0 ≤ h < 1, through h^12: below 1 the library forms cancel.
float layered_sinhc_series(float h) {
    float t = h * h;
    float s = 1.0 + t / 156.0;
    s = 1.0 + t / 110.0 * s;
    s = 1.0 + t / 72.0 * s;
    s = 1.0 + t / 42.0 * s;
    s = 1.0 + t / 20.0 * s;
    return 1.0 + t / 6.0 * s;
}

float layered_sinc_series(float h) {
    float t = h * h;
    float s = 1.0 - t / 156.0;
    s = 1.0 - t / 110.0 * s;
    s = 1.0 - t / 72.0 * s;
    s = 1.0 - t / 42.0 * s;
    s = 1.0 - t / 20.0 * s;
    return 1.0 - t / 6.0 * s;
}

// δ(ȳ)·sinh(h)/h, h = |Δy|/2H; from h = 1 the form that cannot overflow.
float layered_exponential(float y0, float dy) {
    float rho = u_layer.x, base = u_layer.y, scale = u_layer.z;
    float h = abs(dy * 0.5) / scale;
    if (h < LAYERED_SERIES_LIMIT) {
        float mid = y0 + dy * 0.5;
        return rho * exp(min(-(mid - base) / scale, LAYERED_EXPONENT_CAP))
            * layered_sinhc_series(h);
    }
    float low = y0 + min(dy, 0.0);
    float d = h + h;
    return rho * exp(min(-(low - base) / scale, LAYERED_EXPONENT_CAP))
        * ((1.0 - exp(-d)) / d);
}

// The overlap [a, b] of the segment's heights with the band, a fraction `inside` of it,
// has the mean δ(mid)·sin(h)/h with h = π(b − a)/2T.
float layered_band(float y0, float dy) {
    float rho = u_layer.x, base = u_layer.y, thickness = u_layer.z;
    float y1 = y0 + dy;
    float low = min(y0, y1), high = max(y0, y1);
    float top = base + thickness;
    float a = clamp(low, base, top), b = clamp(high, base, top);
    float u = ((a + b) * 0.5 - base) / thickness;
    u = min(u, 1.0 - u);
    float h = (0.5 * LAYERED_PI) * (b - a) / thickness;
    float sinc = h < LAYERED_SERIES_LIMIT ? layered_sinc_series(h) : sin(h) / h;
    float inside;
    if (high > low) {
        inside = (b - a) / (high - low);
    } else {
        inside = (low >= base && low <= top) ? 1.0 : 0.0;
    }
    return rho * sin(LAYERED_PI * u) * sinc * inside;
}

// Piecewise linear: each piece's mean is its value at its mid-height.
float layered_ramp(float y0, float dy) {
    float rho = u_layer.x, floor_y = u_layer.y, top = u_layer.z;
    float y1 = y0 + dy;
    float low = min(y0, y1), high = max(y0, y1);
    if (high > low) {
        float below = min(high, floor_y) - min(low, floor_y);
        float a = clamp(low, floor_y, top), b = clamp(high, floor_y, top);
        float ramp = (b - a) * ((top - (a + b) * 0.5) / (top - floor_y));
        return rho * ((below + ramp) / (high - low));
    }
    return rho * clamp((top - low) / (top - floor_y), 0.0, 1.0);
}

float layered_mean_density(float y0, float dy) {
    int profile = int(u_profile);
#ifdef LAYERED_TABLE
    if (profile == 3) {
        return layered_table_mean(y0, dy); // glsl/medium/layered_table.glsl
    }
#endif
    if (profile == 0) {
        return layered_exponential(y0, dy);
    }
    if (profile == 1) {
        return layered_band(y0, dy);
    }
    return layered_ramp(y0, dy);
}

MediumSample medium_sample(ivec2 pixel, float depth) {
    // The fragment is at brume_eye + brume_ray·z: only its distance and its rise are
    // needed, and the rise is taken as ray.y·z, not as a difference of heights.
    float z = brume_eye_depth(clamp(depth, 0.0, 1.0));
    float l = length(brume_ray) * z;
    float mean = layered_mean_density(brume_eye.y, brume_ray.y * z);
    MediumSample m;
    m.transmission = vec3(exp(-l * mean));
    m.inscatter = u_fog_colour;
    float blur_depth = u_albedo * min(mean * min(l, u_range_unit), LAYERED_MAX_BLUR_DEPTH);
    m.sigma = brume_blur_scale(u_lambda, l / u_range_unit, blur_depth);
    return m;
}
