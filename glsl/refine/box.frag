// Guided refinement, passes 2 and 4: the mean over a (2r + 1)-tap line, horizontal or
// vertical, of the four channels, counting only taps inside the grid (He et al.'s
// normalisation by the box of ones: the borders are not darkened).

uniform sampler2D u_source;
uniform ivec2 u_size;
uniform ivec2 u_step;    // (1, 0) or (0, 1)
uniform int u_radius;

out vec4 o_mean;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 sum = vec4(0.0);
    float n = 0.0;
    for (int k = -u_radius; k <= u_radius; ++k) {
        ivec2 q = p + k * u_step;
        if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, u_size))) {
            sum += texelFetch(u_source, q, 0);
            n += 1.0;
        }
    }
    o_mean = sum / n;
}
