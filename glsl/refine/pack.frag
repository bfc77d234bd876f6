// Guided refinement, pass 1 of 4 (He & Sun's fast guided filter, 2015): on the
// low-resolution grid, each cell's guide I (the colour's sRGB-encoded luminance, averaged
// over the cell's full-resolution pixels) and its log range p (the range texture's own
// value where the range is on this grid, a depth map smaller than the image; else the mean
// of log range over the cell), written as (I, p, I·p, I²) for the box means.

uniform sampler2D u_colour;   // full resolution, RGB
uniform sampler2D u_range;    // R: range > 0, on the low grid or at full resolution
uniform ivec2 u_colour_size;
uniform vec2 u_cell;          // full-resolution pixels per low-resolution cell (x, y)
uniform bool u_colour_srgb;   // the colour texture holds sRGB-encoded values already
uniform bool u_range_full;    // the range is at full resolution (averaged per cell)

out vec4 o_moments;

float guide_at(ivec2 q) {
    vec3 c = texelFetch(u_colour, q, 0).rgb;
    if (!u_colour_srgb) {
        c = linear_to_srgb(c);
    }
    return dot(clamp(c, 0.0, 1.0), vec3(0.2126, 0.7152, 0.0722));
}

void main() {
    ivec2 cell = ivec2(gl_FragCoord.xy);
    // The cell's full-resolution pixels: [floor(i·s), floor((i + 1)·s)), at least one.
    ivec2 lo = ivec2(floor(vec2(cell) * u_cell));
    ivec2 hi = max(ivec2(floor(vec2(cell + 1) * u_cell)), lo + 1);
    hi = min(hi, u_colour_size);
    float guide = 0.0;
    float log_range = 0.0;
    for (int y = lo.y; y < hi.y; ++y) {
        for (int x = lo.x; x < hi.x; ++x) {
            guide += guide_at(ivec2(x, y));
            if (u_range_full) {
                log_range += log(texelFetch(u_range, ivec2(x, y), 0).r);
            }
        }
    }
    float n = float((hi.x - lo.x) * (hi.y - lo.y));
    float i = guide / n;
    float p = u_range_full ? log_range / n : log(texelFetch(u_range, cell, 0).r);
    o_moments = vec4(i, p, i * p, i * i);
}
