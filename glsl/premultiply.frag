// Pass 1 (paper 000, eq. 1-2): F = τ·(E, 1) with τ = exp(−κ·R), κ = κa + κs in units of
// the normalised range R ∈ [0, 1]. E is linear light.
precision highp float;
precision highp sampler2D;

uniform sampler2D u_image;   // linear RGB in .rgb
uniform sampler2D u_range;   // normalised range R in .r
uniform float u_extinction;  // κa + κs

out vec4 o_f;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 e = texelFetch(u_image, p, 0).rgb;
    float tau = exp(-u_extinction * texelFetch(u_range, p, 0).r);
    o_f = vec4(tau * e, tau);
}
