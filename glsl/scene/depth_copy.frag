// Copies the scene's depth texture into a float colour target, texel for texel, so that
// it can be read back with glReadPixels (GLES does not read depth buffers everywhere).

uniform sampler2D u_depth;

out vec4 frag_depth;

void main() {
    frag_depth = vec4(texelFetch(u_depth, ivec2(gl_FragCoord.xy), 0).r, 0.0, 0.0, 1.0);
}
