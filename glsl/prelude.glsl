// Put before every pass after the #version line and the #defines: precisions, then the
// sRGB transfer functions (IEC 61966-2-1) for host textures and framebuffers in 8 bits.
precision highp float;
precision highp int;
precision highp sampler2D;

vec3 srgb_to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(0.04045, c));
}

vec3 linear_to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
