// Pass N+2 (paper 000, eq. 4): out = F.rgb + (1 − τ_blurred)·B, with τ_blurred the alpha of
// the diffused pre-multiplied image, never the sharp τ.
precision highp float;
precision highp sampler2D;

uniform sampler2D u_f;
uniform vec3 u_airlight;  // linear RGB

out vec4 o_colour;

void main() {
    vec4 f = texelFetch(u_f, ivec2(gl_FragCoord.xy), 0);
    o_colour = vec4(f.rgb + (1.0 - f.a) * u_airlight, 1.0);
}
