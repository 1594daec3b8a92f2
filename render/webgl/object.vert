// Mesh vertices in the z-up world frame (the page's mesh is already centred and scaled).
in vec3 aPosition;
in vec3 aNormal;
uniform mat4 uViewProj;
out vec3 vPosition;
out vec3 vNormal;

void main() {
  vPosition = aPosition;
  vNormal = aNormal;
  gl_Position = uViewProj * vec4(aPosition, 1.0);
}
