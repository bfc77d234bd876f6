// Joint bilateral upsampling, pass 1 of 2 (Kopf et al. 2007): on the depth map's own grid,
// each cell's colour (the sRGB-encoded colour averaged over the cell's full-resolution
// pixels) and its log range, written as (r, g, b, log range).

uniform sampler2D u_colour;   // full resolution, RGB
uniform sampler2D u_range;    // R: range > 0, on this grid
uniform ivec2 u_colour_size;
uniform vec2 u_cell;          // full-resolution pixels per cell (x, y)
uniform bool u_colour_srgb;   // the colour texture holds sRGB-encoded values already

out vec4 o_cell;

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
}
