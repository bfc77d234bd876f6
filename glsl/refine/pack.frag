// Guided refinement, pass 1 (He & Sun's fast guided filter, 2015): on the low-resolution
// grid, each cell's guide I (the colour's sRGB-encoded values less 0.5, averaged over the
// cell's full-resolution pixels) and its log range p (the range texture's own value where
// the range is on this grid, a depth map smaller than the image; else the mean of log range
// over the cell), written as the moments the windows' means need, in four targets:
// (I, p), (I·p, I_r²), (I_r·I_g, I_r·I_b, I_g², I_g·I_b), (I_b², 0, 0, 0).

uniform sampler2D u_colour;   // full resolution, RGB
uniform sampler2D u_range;    // R: range > 0, on the low grid or at full resolution
uniform ivec2 u_colour_size;
uniform vec2 u_cell;          // full-resolution pixels per low-resolution cell (x, y)
uniform bool u_colour_srgb;   // the colour texture holds sRGB-encoded values already
uniform bool u_range_full;    // the range is at full resolution (averaged per cell)

layout(location = 0) out vec4 o_guide_range;
layout(location = 1) out vec4 o_cross;
layout(location = 2) out vec4 o_products;
layout(location = 3) out vec4 o_blue;

// The guide, centred: its covariance in f32 loses less to cancellation (refine::GUIDE_CENTRE).
vec3 guide_at(ivec2 q) {
    vec3 c = texelFetch(u_colour, q, 0).rgb;
    c = u_colour_srgb ? clamp(c, 0.0, 1.0) : linear_to_srgb(c);
    return c - 0.5;
}

void main() {
    ivec2 cell = ivec2(gl_FragCoord.xy);
    // The cell's full-resolution pixels: [floor(i·s), floor((i + 1)·s)), at least one.
    ivec2 lo = ivec2(floor(vec2(cell) * u_cell));
    ivec2 hi = max(ivec2(floor(vec2(cell + 1) * u_cell)), lo + 1);
    hi = min(hi, u_colour_size);
    vec3 guide = vec3(0.0);
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
    vec3 i = guide / n;
    float p = u_range_full ? log_range / n : log(texelFetch(u_range, cell, 0).r);
    o_guide_range = vec4(i, p);
    o_cross = vec4(i * p, i.r * i.r);
    o_products = vec4(i.r * i.g, i.r * i.b, i.g * i.g, i.g * i.b);
    o_blue = vec4(i.b * i.b, 0.0, 0.0, 0.0);
}
