// Joint bilateral upsampling, pass 1 of 3 (Kopf et al. 2007): on the depth map's own grid,
// each cell's colour (the sRGB-encoded colour averaged over the cell's full-resolution
// pixels) and its log range, written as (r, g, b, log range); and whether the 6 x 6 cells
// of the window that starts two cells before it (a pixel's in upsample.frag) are flat (log
// ranges within u_flat_spread of each other) or smooth (no second difference of log range
// along a row or a column of the window over u_smooth_curvature) (1) or neither (0): such
// a pixel takes their bilinear interpolation in interpolate.frag (`interpolated_windows`
// in src/refine/upsample.rs, the CPU reference).

uniform sampler2D u_colour;   // full resolution, RGB
uniform sampler2D u_range;    // R: range > 0, on this grid
uniform ivec2 u_colour_size;
uniform vec2 u_cell;          // full-resolution pixels per cell (x, y)
uniform bool u_colour_srgb;   // the colour texture holds sRGB-encoded values already
uniform float u_flat_spread;
uniform float u_smooth_curvature;

layout(location = 0) out vec4 o_cell;
layout(location = 1) out vec4 o_interpolated;

vec3 encoded_at(ivec2 q) {
    vec3 c = texelFetch(u_colour, q, 0).rgb;
    return u_colour_srgb ? clamp(c, 0.0, 1.0) : linear_to_srgb(c);
}

void main() {
    ivec2 cell = ivec2(gl_FragCoord.xy);
    ivec2 lo = ivec2(floor(vec2(cell) * u_cell));
    ivec2 hi = min(max(ivec2(floor(vec2(cell + 1) * u_cell)), lo + 1), u_colour_size);
    vec3 sum = vec3(0.0);
    for (int y = lo.y; y < hi.y; ++y) {
        for (int x = lo.x; x < hi.x; ++x) {
            sum += encoded_at(ivec2(x, y));
        }
    }
    float n = float((hi.x - lo.x) * (hi.y - lo.y));
    o_cell = vec4(sum / n, log(texelFetch(u_range, cell, 0).r));
    ivec2 last = textureSize(u_range, 0) - 1;
    // Constant indices once the loops are unrolled: the window stays in registers.
    float v[36];
    float least = 1e30;
    float largest = -1e30;
    for (int j = 0; j < 6; ++j) {
        for (int i = 0; i < 6; ++i) {
            // Clamped: an edge cell again changes neither bound.
            ivec2 q = clamp(cell + ivec2(i - 2, j - 2), ivec2(0), last);
            v[j * 6 + i] = log(texelFetch(u_range, q, 0).r);
            least = min(least, v[j * 6 + i]);
            largest = max(largest, v[j * 6 + i]);
        }
    }
    // The window's first and last cells of a line, and those outside the grid, are the
    // middle of no three.
    ivec2 first = max(ivec2(2) - cell, ivec2(0)) + 1;
    ivec2 stop = min(last - cell + 2, ivec2(5));
    bool unbent = true;
    for (int j = 0; j < 6; ++j) {
        for (int i = 1; i < 5; ++i) {
            if (j >= first.y - 1 && j <= stop.y && i >= first.x && i < stop.x) {
                float across = v[j * 6 + i - 1] - 2.0 * v[j * 6 + i] + v[j * 6 + i + 1];
                unbent = unbent && abs(across) <= u_smooth_curvature;
            }
            // The same with rows and columns swapped.
            if (j >= first.x - 1 && j <= stop.x && i >= first.y && i < stop.y) {
                float down = v[(i - 1) * 6 + j] - 2.0 * v[i * 6 + j] + v[(i + 1) * 6 + j];
                unbent = unbent && abs(down) <= u_smooth_curvature;
            }
        }
    }
    bool within_spread = largest - least <= u_flat_spread;
    o_interpolated = vec4(within_spread || unbent ? 1.0 : 0.0, 0.0, 0.0, 1.0);
}
