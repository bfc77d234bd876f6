// What every medium's shader sees before its own source (src/medium/mod.rs has the
// contract). A medium defines
//     MediumSample medium_sample(ivec2 pixel, float depth);
// with `depth` the .r of the host's depth or range texture at `pixel`.
struct MediumSample {
    vec3 transmission; // τ per channel, in [0, 1]
    vec3 inscatter;    // L∞, linear RGB
    float sigma;       // blur scale (px), ≥ brume_sigma0
};

uniform float brume_sigma0; // inner scale σ0 of the input (px)
uniform ivec2 brume_size;   // image size (px)
