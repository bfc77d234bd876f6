// The scene's meshes (objects and ground): world-space vertices in, the clip position by
// one view-projection matrix (the camera's projection × view, computed in f64 on the CPU).

uniform mat4 u_view_projection;

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_colour;

out vec3 v_world;
out vec3 v_normal;
out vec4 v_colour;

void main() {
    v_world = a_position;
    v_normal = a_normal;
    v_colour = a_colour;
    gl_Position = u_view_projection * vec4(a_position, 1.0);
}
