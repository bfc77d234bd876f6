// Paper 003's tabulated height profile (sec. 3.2; src/medium/layered/table.rs has the
// derivation and the f64 twin: keep the two identical). κ and its integral K at the
// nodes of a uniform grid in height, read by texelFetch (exact, unlike the filtering
// units' reduced-precision weights) and interpolated here: κ linearly in each cell, K
// exactly (the trapezoid of a linear piece). Constant beyond the grid's ends.
#define LAYERED_TABLE 1
uniform sampler2D u_table_density;  // κ at node j, at texel (j mod width, j div width)
uniform sampler2D u_table_integral; // K at node j: ∫ κ from the first node
uniform vec4 u_table_grid;          // (first height, 1 / spacing, spacing, last node index)
uniform vec3 u_table_ends;          // (last height, κ below the first, κ above the last)
uniform float u_table_width;        // texels per row of the two textures

float layered_table_fetch(sampler2D table, int j) {
    int width = int(u_table_width);
    return texelFetch(table, ivec2(j % width, j / width), 0).r;
}

// The cell holding y (origin ≤ y ≤ top) and κ(y).
int layered_table_cell(float y) {
    float t = (y - u_table_grid.x) * u_table_grid.y;
    return clamp(int(floor(t)), 0, int(u_table_grid.w) - 1);
}

float layered_table_density_in(int i, float y) {
    float f = (y - u_table_grid.x) * u_table_grid.y - float(i);
    return mix(layered_table_fetch(u_table_density, i),
               layered_table_fetch(u_table_density, i + 1), f);
}

// ∫_a^b κ for origin ≤ a ≤ b ≤ top: partial cells by their trapezoids, whole cells by K.
float layered_table_integral(float a, float b) {
    int ia = layered_table_cell(a), ib = layered_table_cell(b);
    float ka = layered_table_density_in(ia, a), kb = layered_table_density_in(ib, b);
    if (ia == ib) {
        return (b - a) * 0.5 * (ka + kb);
    }
    float node_a = u_table_grid.x + float(ia + 1) * u_table_grid.z;
    float node_b = u_table_grid.x + float(ib) * u_table_grid.z;
    return (node_a - a) * 0.5 * (ka + layered_table_fetch(u_table_density, ia + 1))
        + (layered_table_fetch(u_table_integral, ib)
           - layered_table_fetch(u_table_integral, ia + 1))
        + (b - node_b) * 0.5 * (layered_table_fetch(u_table_density, ib) + kb);
}

// The mean of κ from y0 to y0 + dy; κ(y0) when dy = 0.
float layered_table_mean(float y0, float dy) {
    float y1 = y0 + dy;
    float low = min(y0, y1), high = max(y0, y1);
    float lo = u_table_grid.x, hi = u_table_ends.x;
    float below = (min(high, lo) - min(low, lo)) * u_table_ends.y;
    float above = (max(high, hi) - max(low, hi)) * u_table_ends.z;
    float a = clamp(low, lo, hi), b = clamp(high, lo, hi);
    if (high > low) {
        return (below + layered_table_integral(a, b) + above) / (high - low);
    }
    return layered_table_density_in(layered_table_cell(a), a);
}
