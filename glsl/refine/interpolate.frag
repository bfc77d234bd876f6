// Joint bilateral upsampling, pass 2 of 3, at full resolution: where cells.frag found the
// window of a pixel's 6 x 6 cells flat or smooth (no depth edge for the colour to place),
// the pixel takes the bilinear interpolation of their log ranges, from 4 cells instead of
// 36, and depth 0; every other pixel gets depth 1, which lets the depth test pass it to
// pass 3 (upsample.frag, the 36 taps). A branch does not save the 36 taps' cost where the
// pixels shaded together split between its sides; a depth test rejects whole blocks
// before they are shaded (on the 4000 x 3000 street frame 18 % of the 4 x 4 blocks reach
// pass 3).

uniform sampler2D u_cells;        // (r, g, b, log range) per cell
uniform sampler2D u_interpolated; // R: 1 where the window two cells before is flat or smooth
uniform ivec2 u_low_size;
uniform vec2 u_scale;             // cells per full-resolution pixel (x, y)

out vec4 o_range;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec2 centre = (vec2(p) + 0.5) * u_scale - 0.5;
    ivec2 base = ivec2(floor(centre));
    ivec2 last = u_low_size - 1;
    // Only between the outer cells' centres, as the CPU reference, whose rows run the
    // other way: a window clamped at the edge would not be the same cells there.
    bool inner = all(greaterThanEqual(base, ivec2(0))) && all(lessThan(base, last));
    if (inner && texelFetch(u_interpolated, clamp(base, ivec2(0), last), 0).r > 0.5) {
        vec2 t = centre - vec2(base);
        ivec2 hi = base + 1;
        float top = mix(texelFetch(u_cells, base, 0).a,
                        texelFetch(u_cells, ivec2(hi.x, base.y), 0).a, t.x);
        float bottom = mix(texelFetch(u_cells, ivec2(base.x, hi.y), 0).a,
                           texelFetch(u_cells, hi, 0).a, t.x);
        o_range = vec4(exp(mix(top, bottom, t.y)), 0.0, 0.0, 1.0);
        gl_FragDepth = 0.0;
    } else {
        o_range = vec4(0.0); // pass 3's to write
        gl_FragDepth = 1.0;
    }
}
