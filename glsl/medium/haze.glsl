// Paper 000's haze (src/medium/haze.rs): Beer-Lambert transmission (eq. 1) per channel,
// a constant airlight (eq. 4) and the blur scale of eq. 7 in normalised range.
uniform vec3 u_extinction;   // (κa + κs)·tint, per unit of normalised range
uniform float u_range_scale; // 1 / (range units per unit of normalised range)
uniform float u_sigma_span;  // σmax − σ0 = λ·√κs
uniform vec3 u_airlight;     // B, linear RGB

MediumSample medium_sample(ivec2 pixel, float depth) {
    float r = depth * u_range_scale;
    MediumSample m;
    m.transmission = exp(-u_extinction * r);
    m.inscatter = u_airlight;
    m.sigma = brume_sigma0 + pow(clamp(r, 0.0, 1.0), 1.5) * u_sigma_span;
    return m;
}
