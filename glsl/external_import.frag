// The import pass of an external image (a camera frame from a SurfaceTexture or an
// AHardwareBuffer, bound by the host to GL_TEXTURE_EXTERNAL_OES): sampled once per texel
// of brume's SRGB8_ALPHA8 copy, which the other passes then read with texelFetch.
// Assembled by src/pipeline/external.rs as: #version, this file's #extension line (it must
// come before any other token, the prelude's precision statements included), prelude.glsl,
// then the rest of this file.
#extension GL_OES_EGL_image_external_essl3 : require

// highp: the default precision of samplerExternalOES is lowp, which may return 8 bits or
// fewer of the frame's values.
uniform highp samplerExternalOES u_external;
uniform mat4 u_transform; // texture-coordinate transform (SurfaceTexture.getTransformMatrix)
uniform vec2 u_size;      // size of the copy (px)

layout(location = 0) out vec4 o_colour;

void main() {
    // gl_FragCoord.xy is a texel centre (i + ½): with the identity transform, each texel
    // of the copy samples the centre of the source texel of the same index, where a
    // bilinear filter returns that texel alone.
    vec2 uv = gl_FragCoord.xy / u_size;
    vec4 c = texture(u_external, (u_transform * vec4(uv, 0.0, 1.0)).xy);
    // Camera frames are sRGB-encoded; the SRGB8_ALPHA8 target encodes linear values back
    // on write, and brume's passes read them decoded (linear) by GL.
    o_colour = vec4(srgb_to_linear(clamp(c.rgb, 0.0, 1.0)), c.a);
}
