// A blur to one scale everywhere through a uniform filter, with no in-scattered light
// (src/medium/uniform.rs): what paper 000's accuracy experiment measures.
uniform float u_sigma;        // σ (px), ≥ σ0
uniform vec3 u_transmission;  // τ per channel

MediumSample medium_sample(ivec2 pixel, float depth) {
    return MediumSample(u_transmission, vec3(0.0), u_sigma);
}
