// Joint bilateral upsampling, pass 3 of 3, at full resolution, over the pixels the depth
// test lets through (those interpolate.frag did not interpolate): the log range of the
// 6 x 6 cells around the pixel, each weighted by its distance (a Gaussian of one cell)
// and by how far its colour is from the pixel's (a Gaussian of u_sigma_colour in
// sRGB-encoded values): a pixel takes the range of the nearby cells that look like it,
// so an edge of the image is an edge of the range even where the coarse cells straddle
// it. The mean is then moved by two mean-shift steps (a Gaussian of SHIFT_SIGMA in log
// range) toward the surface that holds most of the weight, so that taps of two surfaces
// the colour lets through do not make a range neither has (`shift_to_dominant_surface`
// in src/refine/upsample.rs, the CPU reference).

const float SHIFT_SIGMA = 0.3;
const int SHIFT_STEPS = 2;
// The taps' weighted standard deviation in log range below which the mean is kept (one
// surface), so that most pixels skip the steps.
const float SHIFT_MIN_SPREAD = 0.03;

uniform sampler2D u_colour;
uniform sampler2D u_cells;        // (r, g, b, log range) per cell
uniform ivec2 u_low_size;
uniform vec2 u_scale;             // cells per full-resolution pixel (x, y)
uniform bool u_colour_srgb;
uniform float u_sigma_colour;

out vec4 o_range;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 c = texelFetch(u_colour, p, 0).rgb;
    vec3 colour = u_colour_srgb ? clamp(c, 0.0, 1.0) : linear_to_srgb(c);
    vec2 centre = (vec2(p) + 0.5) * u_scale - 0.5;
    ivec2 base = ivec2(floor(centre));
    ivec2 last = u_low_size - 1;
    float inv_colour = 1.0 / (2.0 * u_sigma_colour * u_sigma_colour);
    float sum = 0.0;
    float weight = 0.0;
    float nearest = 0.0;
    float nearest_d2 = 1e30;
    // Each tap has a fixed slot (a cell outside the grid weighs 0) so that every index is
    // known when the loops are unrolled: the arrays stay in registers instead of memory
    // indexed per pixel, which llvmpipe and many mobile GPUs make slow.
    float tap_weight[36];
    float tap_log_range[36];
    for (int j = -2; j <= 3; ++j) {
        for (int i = -2; i <= 3; ++i) {
            int k = (j + 2) * 6 + (i + 2);
            ivec2 q = base + ivec2(i, j);
            bool inside = all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, u_low_size));
            vec4 cell = texelFetch(u_cells, clamp(q, ivec2(0), last), 0);
            vec2 d = vec2(q) - centre;
            vec3 dc = colour - cell.rgb;
            float w = inside ? exp(-0.5 * dot(d, d) - dot(dc, dc) * inv_colour) : 0.0;
            sum += w * cell.a;
            weight += w;
            tap_weight[k] = w;
            tap_log_range[k] = cell.a;
            if (inside && dot(d, d) < nearest_d2) {
                nearest_d2 = dot(d, d);
                nearest = cell.a;
            }
        }
    }
    // A colour unlike every cell around (all weights underflow): the nearest cell's.
    float log_range = nearest;
    if (weight > 1e-30) {
        log_range = sum / weight;
        float spread = 0.0;
        for (int k = 0; k < 36; ++k) {
            float dv = tap_log_range[k] - log_range;
            spread += tap_weight[k] * dv * dv;
        }
        int steps = spread > SHIFT_MIN_SPREAD * SHIFT_MIN_SPREAD * weight ? SHIFT_STEPS : 0;
        float inv_shift = 1.0 / (2.0 * SHIFT_SIGMA * SHIFT_SIGMA);
        for (int step = 0; step < steps; ++step) {
            float s = 0.0;
            float wsum = 0.0;
            for (int k = 0; k < 36; ++k) {
                float dv = tap_log_range[k] - log_range;
                float w = tap_weight[k] * exp(-dv * dv * inv_shift);
                s += w * dv;
                wsum += w;
            }
            // Every tap too far from the estimate to count: keep it.
            if (wsum <= 1e-30) {
                break;
            }
            log_range += s / wsum;
        }
    }
    o_range = vec4(exp(log_range), 0.0, 0.0, 1.0);
}
