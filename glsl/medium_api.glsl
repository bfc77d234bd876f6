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

// A medium with a camera (Medium::frame_camera in Rust) reads a depth buffer: set from
// the camera for each frame (src/camera.rs), and zero otherwise. Any perspective
// projection: standard or reversed-Z, finite or infinite far plane, off-centre, either
// clip depth convention (MatrixCamera in src/camera.rs).
in vec3 brume_ray;                  // eye-to-fragment vector (world), eye depth 1
uniform vec4 brume_depth_constants; // (a, k, c, max): eye depth = a / ((d − k) − c) ≤ max
uniform vec3 brume_eye;             // the camera's position (world)

// Linear eye depth of window depth d (DepthModel::eye_depth in src/camera.rs: keep the two
// identical). k + c is the window depth at infinite distance, split so that f32 keeps the
// digits of c near the far plane (d − k is exact); a pixel at an infinite far plane, or
// beyond the sky depth, gets the sky depth `max`.
float brume_eye_depth(float d) {
    float den = (clamp(d, 0.0, 1.0) - brume_depth_constants.y) - brume_depth_constants.z;
    float t = brume_depth_constants.x / (den == 0.0 ? 1.0 : den);
    return (den == 0.0 || !(t > 0.0)) ? brume_depth_constants.w
                                      : min(t, brume_depth_constants.w);
}

// The blur scale from a scattering optical depth `ds` accumulated over a normalised
// distance `r` (blur_from_optical_depth in src/medium/mod.rs: keep the two identical).
float brume_blur_scale(float lambda, float r, float ds) {
    return brume_sigma0 + lambda * clamp(r, 0.0, 1.0) * sqrt(max(ds, 0.0));
}
