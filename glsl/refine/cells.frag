// Joint bilateral upsampling, pass 1 of 2 (Kopf et al. 2007): on the depth map's own grid,
// each cell's colour (the sRGB-encoded colour averaged over the cell's full-resolution
// pixels) and its log range, written as (r, g, b, log range); and whether the 6 x 6 cells
// of the window that starts two cells before it (a pixel's in upsample.frag) have log
// ranges within u_flat_spread of each other (1) or not (0): such a pixel takes their
// bilinear interpolation (`flat_windows` in src/refine/upsample.rs, the CPU reference).

uniform sampler2D u_colour;   // full resolution, RGB
uniform sampler2D u_range;    // R: range > 0, on this grid
uniform ivec2 u_colour_size;
uniform vec2 u_cell;          // full-resolution pixels per cell (x, y)
uniform bool u_colour_srgb;   // the colour texture holds sRGB-encoded values already
uniform float u_flat_spread;

layout(location = 0) out vec4 o_cell;
layout(location = 1) out vec4 o_flat;

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
    float least = 1e30;
    float largest = -1e30;
    for (int j = -2; j <= 3; ++j) {
        for (int i = -2; i <= 3; ++i) {
            // Clamped: an edge cell again changes neither bound.
            ivec2 q = clamp(cell + ivec2(i, j), ivec2(0), last);
            float v = log(texelFetch(u_range, q, 0).r);
            least = min(least, v);
            largest = max(largest, v);
        }
    }
    o_flat = vec4(largest - least <= u_flat_spread ? 1.0 : 0.0, 0.0, 0.0, 1.0);
}
