// Paper 001's distance fog (src/medium/distance.rs has the formulas and where they depart
// from the paper): density from the distance to the eye (eq. 1-2), varied by a drifting
// tiling noise (eq. 9-10, Listing 1), capped; the fog colour brightened toward a light
// beyond a start distance (eq. 5-8). τ = 1 − F, L∞ = C_fog', σ from −ln(1 − F).
uniform vec3 u_fog_shape;      // (start distance, 1 / blend distance, exponent)
uniform float u_max_density;   // the cap on F, < 1
uniform vec3 u_fog_colour;     // C_fog, linear RGB
uniform vec3 u_light;          // unit vector toward the light (world)
uniform vec2 u_scatter;        // (scatter start distance, scatter exponent)
uniform vec3 u_scatter_colour; // C_scatter, linear RGB
uniform float u_noise_on;      // 1: read u_noise; 0: no noise, u_noise is never read
uniform sampler2D u_noise;     // tiling noise, .r in [0, 1]
uniform vec2 u_noise_origin;   // (eye.xz + speed.xz·time) / size, reduced to [0, 1)
uniform float u_noise_scale;   // 1 / world size of a tile
uniform vec2 u_noise_range;    // density factor at noise 0 and 1 (low, high)
uniform float u_noise_colour;  // s: the fog colour is scaled by 1 + s·(2·noise − 1)
uniform vec2 u_blur;           // (λ, 1 / range unit)

MediumSample medium_sample(ivec2 pixel, float depth) {
    // Eye to point: the ray times the linear eye depth (the far end of the depth range is
    // the far plane, or an infinite projection's sky depth). Its f32 precision matters
    // here: an error of a metre at 1 km would shift the noise by texels.
    float z = brume_eye_depth(clamp(depth, 0.0, 1.0));
    vec3 offset = brume_ray * z;
    float l = length(offset);
    float density = pow(max((l - u_fog_shape.x) * u_fog_shape.y, 0.0), u_fog_shape.z);
    // A uniform condition: no texture read at all without noise.
    float tint = 1.0;
    if (u_noise_on > 0.5) {
        vec2 uv = u_noise_origin + offset.xz * u_noise_scale;
        float noise = textureLod(u_noise, uv, 0.0).r;
        density *= mix(u_noise_range.x, u_noise_range.y, noise);
        // Paper 001 sec. 3.3: the noise varies the colour too (FogNoise::colour_factor).
        tint = 1.0 + u_noise_colour * (2.0 * noise - 1.0);
    }
    density = clamp(density, 0.0, u_max_density);
    float towards = clamp(dot(normalize(brume_ray), u_light), 0.0, 1.0);
    float scatter = pow(towards, u_scatter.y) * clamp((l - u_scatter.x) / l, 0.0, 1.0);
    MediumSample m;
    m.transmission = vec3(1.0 - density);
    m.inscatter = (u_fog_colour + u_scatter_colour * scatter) * tint;
    m.sigma = brume_blur_scale(u_blur.x, l * u_blur.y, -log(1.0 - density));
    return m;
}
