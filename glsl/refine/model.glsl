// Guided refinement: the local linear model p ≈ a·I + b of one window with a colour guide
// (He et al. 2013, eq. 14): a = (Σ + εU)⁻¹ cov(I, p), b = mean(p) − a·mean(I), Σ the 3 x 3
// covariance of the window's colour, from the window's means of the moments pack.frag
// writes. Put before box.frag for its last pass over the moments, which it turns into the
// pass that writes the models.

#define WINDOW_MODEL

uniform float u_epsilon;

// guide_range: means of (I, p); cross_terms: of (I·p, I_r²); products: of (I_r·I_g,
// I_r·I_b, I_g², I_g·I_b); bb: of I_b². Returns (a_r, a_g, a_b, b).
vec4 window_model(vec4 guide_range, vec4 cross_terms, vec4 products, float bb) {
    vec3 i = guide_range.xyz;
    float p = guide_range.w;
    vec3 cov_ip = cross_terms.xyz - i * p;
    mat3 sigma = mat3(
        cross_terms.w, products.x, products.y,
        products.x, products.z, products.w,
        products.y, products.w, bb);
    sigma -= outerProduct(i, i);
    sigma += mat3(u_epsilon);
    vec3 a = inverse(sigma) * cov_ip;
    return vec4(a, p - dot(a, i));
}
