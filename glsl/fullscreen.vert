// One triangle that covers the viewport; no vertex buffer (the #version line is added at
// run time for the context). It also hands each fragment its eye-to-fragment ray (paper
// 003, sec. 2.1): the rays at three corners of the image are uniforms, each vertex of the
// triangle gets the ray at its position (the ray is affine in screen space, so the corner
// rays extend exactly to the triangle's vertices beyond the image), and the hardware
// interpolates it. Zero for a medium without a camera.

uniform mat3 brume_corner_rays; // columns: rays at NDC (−1, −1), (1, −1), (−1, 1), world

out vec3 brume_ray;

void main() {
    vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    brume_ray = brume_corner_rays[0]
        + corner.x * (brume_corner_rays[1] - brume_corner_rays[0])
        + corner.y * (brume_corner_rays[2] - brume_corner_rays[0]);
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
