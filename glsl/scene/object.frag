// Boxes and pillars: a flat albedo per object, Lambert + ambient, darker toward the foot
// of the walls (the vertex colour's alpha, a fake contact shadow).

in vec3 v_world;
in vec3 v_normal;
in vec4 v_colour;

out vec4 frag_colour;

void main() {
    vec3 n = normalize(v_normal);
    // The shadow darkens the ambient light and, less, the sun's.
    float foot = v_colour.a;
    vec3 lit = shade(v_colour.rgb, n, foot) * mix(1.0, foot, 0.5);
    frag_colour = vec4(lit, 1.0);
}
