// Guided refinement, pass 3: the local linear model p ≈ a·I + b of each window (He et al.
// 2013, eq. 5-6): a = cov(I, p) / (var(I) + ε), b = mean(p) − a·mean(I).

uniform sampler2D u_means;   // box means of (I, p, I·p, I²)
uniform float u_epsilon;

out vec4 o_coefficients;

void main() {
    vec4 m = texelFetch(u_means, ivec2(gl_FragCoord.xy), 0);
    float variance = max(m.w - m.x * m.x, 0.0);
    float covariance = m.z - m.x * m.y;
    float a = covariance / (variance + u_epsilon);
    o_coefficients = vec4(a, m.y - a * m.x, 0.0, 1.0);
}
