// The sky: one triangle over the viewport at the far plane (z = w: window depth 1.0)
// carrying the view ray, drawn last with the depth test LEQUAL and no depth writes, so
// that it is shaded only where the depth buffer kept its clear value, 1.0.

// The world ray through NDC (x, y) is u_forward + x·u_right + y·u_up.
uniform vec3 u_forward;
uniform vec3 u_right;
uniform vec3 u_up;

out vec3 v_ray;

void main() {
    vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    vec2 ndc = corner * 2.0 - 1.0;
    v_ray = u_forward + ndc.x * u_right + ndc.y * u_up;
    gl_Position = vec4(ndc, 1.0, 1.0);
}
