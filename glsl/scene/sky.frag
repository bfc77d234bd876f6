// The sky's radiance along each pixel's view ray, and the sun's disc.

in vec3 v_ray;

out vec4 frag_colour;

void main() {
    vec3 dir = normalize(v_ray);
    frag_colour = vec4(sky_radiance(dir) + sun_disc(dir), 1.0);
}
