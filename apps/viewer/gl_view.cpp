#include "gl_view.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "camera_control.h"
#include "zeroset/error.h"
#include "zeroset/render/lights.h"

namespace zeroset::viewer {
namespace {

// The shading of zeroset's CPU renderer (Phong, parallel lights, ambient term, front and back
// materials, gamma 2.2), in eye space; shared by the programs below (after their #version
// line). A point is on the front side when the eye lies on the side its normal (∇F) points to.
constexpr const char* kShading = R"(
uniform int u_light_count;
uniform vec3 u_light_dir[4];    // unit, towards the light, eye space
uniform vec3 u_light_color[4];
uniform vec3 u_front_diffuse;
uniform vec3 u_front_params;    // ambient, specular, shininess
uniform vec3 u_back_diffuse;
uniform vec3 u_back_params;

vec3 phong(vec3 n, vec3 to_eye, vec3 diffuse, vec3 params) {
  vec3 c = params.x * diffuse;
  for (int i = 0; i < u_light_count; ++i) {
    float ndl = dot(n, u_light_dir[i]);
    if (ndl <= 0.0) continue;
    c += u_light_color[i] * ndl * diffuse;
    if (params.y > 0.0) {
      float rv = dot(2.0 * ndl * n - u_light_dir[i], to_eye);
      if (rv > 0.0) c += params.y * pow(rv, params.z) * u_light_color[i];
    }
  }
  return c;
}

// Gamma-encoded colour of a point at `pos` (eye space) with normal `normal`.
vec3 shade(vec3 normal, vec3 pos) {
  vec3 to_eye = normalize(-pos);
  float len = length(normal);
  vec3 n = len > 1e-12 ? normal / len : to_eye;
  bool front = dot(n, to_eye) >= 0.0;
  vec3 c = front ? phong(n, to_eye, u_front_diffuse, u_front_params)
                 : phong(-n, to_eye, u_back_diffuse, u_back_params);
  return pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2));
}
)";

// Disk: one point sprite per floater, as wide as the projection of the ball that holds the
// disk; the fragment shader intersects the pixel's eye ray with the disk's plane and keeps
// the pixels within its radius, so every disk appears as the exact ellipse it projects to.
// One primitive and one vertex per floater: software OpenGL spends much of its time per
// primitive and per vertex, and draws these faster than the same disks as quads. A disk is
// flat, so it is shaded once, at its centre, and it keeps the depth of its centre: writing
// each pixel's exact depth made a frame 40% dearer with software OpenGL, and neighbouring
// disks are ordered well by their centres.
constexpr const char* kDiskVertex = R"(
layout(location = 1) in vec3 a_center;
layout(location = 2) in vec3 a_normal;
layout(location = 3) in float a_radius;
uniform mat4 u_view;
uniform mat4 u_proj;
uniform float u_scale;
uniform vec4 u_viewport;  // x, y, width, height in pixels
flat out vec3 v_color;
flat out vec3 v_center;
flat out vec3 v_normal;
flat out float v_radius;
void main() {
  vec4 ce = u_view * vec4(a_center, 1.0);
  vec3 n = mat3(u_view) * normalize(a_normal);
  float r = u_scale * a_radius;
  v_color = shade(n, ce.xyz);
  v_center = ce.xyz;
  v_normal = n;
  v_radius = r;
  gl_Position = u_proj * ce;
  // Seen straight ahead, the ball's projection has the half width r / sqrt(d² - r²) (d its
  // distance, in units of the focal length); at an angle θ off the axis it is stretched by up
  // to 1/cos²θ. 5% and a pixel more cover where it sits off the sprite's centre.
  float d2 = max(dot(ce.xyz, ce.xyz), 1e-12);
  float cos2 = ce.z * ce.z / d2;
  float half_width = r / sqrt(max(d2 - r * r, 1e-12)) / max(cos2, 0.1) * u_proj[1][1] * 0.5 * u_viewport.w;
  gl_PointSize = clamp(2.1 * half_width + 1.0, 1.0, 255.0);
}
)";

constexpr const char* kDiskFragment = R"(
flat in vec3 v_color;
flat in vec3 v_center;
flat in vec3 v_normal;
flat in float v_radius;
uniform mat4 u_proj;
uniform vec4 u_viewport;
out vec4 frag;
void main() {
  vec2 ndc = 2.0 * (gl_FragCoord.xy - u_viewport.xy) / u_viewport.zw - 1.0;
  vec3 dir = vec3(ndc.x / u_proj[0][0], ndc.y / u_proj[1][1], -1.0);
  float facing = dot(dir, v_normal);
  if (abs(facing) < 1e-9) discard;
  vec3 p = dot(v_center, v_normal) / facing * dir;
  vec3 d = p - v_center;
  if (dot(d, d) > v_radius * v_radius) discard;
  frag = vec4(v_color, 1.0);
}
)";

// Points: round sprites of a fixed size in pixels, shaded at their centre.
constexpr const char* kPointVertex = R"(
layout(location = 1) in vec3 a_center;
layout(location = 2) in vec3 a_normal;
uniform mat4 u_view;
uniform mat4 u_proj;
uniform float u_point_size;
flat out vec3 v_color;
void main() {
  vec4 pe = u_view * vec4(a_center, 1.0);
  v_color = shade(mat3(u_view) * a_normal, pe.xyz);
  gl_PointSize = u_point_size;
  gl_Position = u_proj * pe;
}
)";

constexpr const char* kPointFragment = R"(
flat in vec3 v_color;
out vec4 frag;
void main() {
  vec2 q = 2.0 * gl_PointCoord - 1.0;
  if (dot(q, q) > 1.0) discard;
  frag = vec4(v_color, 1.0);
}
)";

// u_depth_bias moves a point's depth (not its place on screen) that far towards the eye: the
// singular set's tubes are tested against an approximation of the surface (see draw_singular).
constexpr const char* kMeshVertex = R"(
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_view;
uniform mat4 u_proj;
uniform float u_depth_bias;
out vec3 v_pos;
out vec3 v_normal;
void main() {
  vec4 pe = u_view * vec4(a_pos, 1.0);
  v_pos = pe.xyz;
  v_normal = mat3(u_view) * a_normal;
  gl_Position = u_proj * pe;
  if (u_depth_bias > 0.0) {
    vec4 nearer = u_proj * vec4(pe.xy, pe.z + u_depth_bias, 1.0);
    gl_Position.z = nearer.z / nearer.w * gl_Position.w;
  }
}
)";

// The mesh is shaded per fragment: its normals (∇F) vary across a triangle.
constexpr const char* kMeshFragment = R"(
in vec3 v_pos;
in vec3 v_normal;
uniform vec4 u_flat_color;  // alpha > 0: this colour instead of shading (wireframe)
out vec4 frag;
void main() {
  frag = u_flat_color.a > 0.0 ? u_flat_color : vec4(shade(v_normal, v_pos), 1.0);
}
)";

// One triangle covering the viewport; the image's row 0 is its top.
constexpr const char* kImageVertex = R"(
out vec2 v_uv;
void main() {
  vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  v_uv = vec2(p.x, 1.0 - p.y);
  gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
}
)";

constexpr const char* kImageFragment = R"(
in vec2 v_uv;
uniform sampler2D u_image;
out vec4 frag;
void main() { frag = vec4(texture(u_image, v_uv).rgb, 1.0); }
)";

constexpr int kMaxLights = 4;
constexpr float kWireColor[4] = {0.08f, 0.08f, 0.1f, 1.0f};
constexpr int kFloaterFloats = 7;  // centre, normal, radius

// Compiles "#version 330 core", the shading functions and `body`.
GLuint compile(GLenum kind, const char* body) {
  const GLuint shader = glCreateShader(kind);
  const char* sources[] = {"#version 330 core\n", kShading, body};
  glShaderSource(shader, 3, sources, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::string log(std::max(length, 1), '\0');
    glGetShaderInfoLog(shader, length, nullptr, log.data());
    glDeleteShader(shader);
    throw Error("OpenGL shader does not compile: " + log);
  }
  return shader;
}

GLuint link(const char* vertex, const char* fragment) {
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex);
  const GLuint fs = compile(GL_FRAGMENT_SHADER, fragment);
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    GLint length = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::string log(std::max(length, 1), '\0');
    glGetProgramInfoLog(program, length, nullptr, log.data());
    glDeleteProgram(program);
    throw Error("OpenGL program does not link: " + log);
  }
  return program;
}

void locate(GLuint id, auto& p) {
  p.id = id;
  p.view = glGetUniformLocation(id, "u_view");
  p.proj = glGetUniformLocation(id, "u_proj");
  p.scale = glGetUniformLocation(id, "u_scale");
  p.point_size = glGetUniformLocation(id, "u_point_size");
  p.viewport = glGetUniformLocation(id, "u_viewport");
  p.flat_color = glGetUniformLocation(id, "u_flat_color");
  p.light_count = glGetUniformLocation(id, "u_light_count");
  p.light_dir = glGetUniformLocation(id, "u_light_dir");
  p.light_color = glGetUniformLocation(id, "u_light_color");
  p.front_diffuse = glGetUniformLocation(id, "u_front_diffuse");
  p.front_params = glGetUniformLocation(id, "u_front_params");
  p.back_diffuse = glGetUniformLocation(id, "u_back_diffuse");
  p.back_params = glGetUniformLocation(id, "u_back_params");
  p.image = glGetUniformLocation(id, "u_image");
  p.depth_bias = glGetUniformLocation(id, "u_depth_bias");
}

// A vertex array of indexed triangles whose vertices are a position and a normal (attributes
// 0 and 1, six floats), as the mesh program reads them.
void make_triangle_arrays(GLuint& vao, GLuint& vbo, GLuint& ebo) {
  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  glGenBuffers(1, &vbo);
  glGenBuffers(1, &ebo);
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        reinterpret_cast<void*>(3 * sizeof(float)));
}

void set_material(GLint diffuse, GLint params, const Material& m) {
  glUniform3f(diffuse, static_cast<float>(m.diffuse.x()), static_cast<float>(m.diffuse.y()),
              static_cast<float>(m.diffuse.z()));
  glUniform3f(params, static_cast<float>(m.ambient), static_cast<float>(m.specular),
              static_cast<float>(m.shininess));
}

float encode_gamma(double linear) {
  return static_cast<float>(std::pow(std::clamp(linear, 0.0, 1.0), 1.0 / 2.2));
}

}  // namespace

GlView::GlView() {
  locate(link(kDiskVertex, kDiskFragment), disks_);
  locate(link(kPointVertex, kPointFragment), points_);
  locate(link(kMeshVertex, kMeshFragment), mesh_);
  locate(link(kImageVertex, kImageFragment), image_);

  // Floaters: one vertex per floater, drawn as disks or as points.
  glGenBuffers(1, &floater_vbo_);
  glGenVertexArrays(1, &floater_vao_);
  glBindVertexArray(floater_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, floater_vbo_);
  const GLsizei stride = kFloaterFloats * sizeof(float);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride, nullptr);
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, stride,
                        reinterpret_cast<void*>(3 * sizeof(float)));
  glEnableVertexAttribArray(3);
  glVertexAttribPointer(3, 1, GL_FLOAT, GL_FALSE, stride,
                        reinterpret_cast<void*>(6 * sizeof(float)));

  make_triangle_arrays(mesh_vao_, mesh_vbo_, mesh_ebo_);
  // The singular set's tubes and spheres, drawn with the mesh's program.
  make_triangle_arrays(singular_vao_, singular_vbo_, singular_ebo_);

  glGenVertexArrays(1, &image_vao_);
  glGenTextures(1, &image_texture_);
  glBindTexture(GL_TEXTURE_2D, image_texture_);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glBindVertexArray(0);
}

GlView::~GlView() {
  glDeleteFramebuffers(1, &scene_fbo_);
  const GLuint renderbuffers[] = {scene_color_, scene_depth_};
  glDeleteRenderbuffers(2, renderbuffers);
  glDeleteTextures(1, &image_texture_);
  const GLuint arrays[] = {floater_vao_, mesh_vao_, singular_vao_, image_vao_};
  glDeleteVertexArrays(4, arrays);
  const GLuint buffers[] = {floater_vbo_, mesh_vbo_, mesh_ebo_, singular_vbo_, singular_ebo_};
  glDeleteBuffers(5, buffers);
  for (const Program* p : {&disks_, &points_, &mesh_, &image_}) glDeleteProgram(p->id);
}

std::vector<double> GlView::scene_key(const ViewerState& state, int width, int height) const {
  // Everything the picture depends on. The frames are compared by address; the GL view holds
  // the uploaded ones, so an address cannot be reused while it is in the key.
  std::vector<double> key = {static_cast<double>(state.mode()), static_cast<double>(width),
                             static_cast<double>(height)};
  const void* frame =
      state.mode() == Mode::kRaytrace   ? static_cast<const void*>(state.preview().get())
      : state.mode() == Mode::kFloaters ? static_cast<const void*>(state.floaters().get())
                                        : static_cast<const void*>(state.mesh().get());
  key.push_back(static_cast<double>(reinterpret_cast<std::uintptr_t>(frame)));
  // The ray tracer draws the singular set into its picture; the GL modes draw it here.
  key.push_back(static_cast<double>(reinterpret_cast<std::uintptr_t>(state.singular().get())));
  const Camera& c = state.camera();
  key.insert(key.end(), {c.azimuth_deg, c.elevation_deg, c.distance, c.fov_deg, c.target.x(),
                         c.target.y(), c.target.z(), state.surface().scene_radius()});
  const DisplaySettings& d = state.display();
  key.insert(key.end(), {static_cast<double>(d.draw_points), d.disk_scale, d.point_size_px,
                         static_cast<double>(d.wireframe)});
  const RenderOptions& look = state.look();
  for (const Material* m : {&look.front, &look.back})
    key.insert(key.end(), {m->diffuse.x(), m->diffuse.y(), m->diffuse.z(), m->ambient, m->specular,
                           m->shininess});
  key.insert(key.end(), {look.background.x(), look.background.y(), look.background.z()});
  for (const Light& l : look.lights)
    key.insert(key.end(), {l.direction.x(), l.direction.y(), l.direction.z(), l.color.x(),
                           l.color.y(), l.color.z(), static_cast<double>(l.follows_camera)});
  return key;
}

void GlView::draw(const ViewerState& state, int x, int y, int width, int height) {
  if (width < 1 || height < 1) return;
  // The scene is drawn into an offscreen buffer only when it changed; other frames (the
  // panel reacting to the mouse) copy it, which with software OpenGL costs far less than
  // drawing ten thousand disks again.
  std::vector<double> key = scene_key(state, width, height);
  if (key != scene_key_) {
    if (width != scene_w_ || height != scene_h_) resize_scene_buffer(width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, scene_fbo_);
    draw_scene(state, width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    scene_key_ = std::move(key);
  }
  glBindFramebuffer(GL_READ_FRAMEBUFFER, scene_fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, width, height, x, y, x + width, y + height, GL_COLOR_BUFFER_BIT,
                    GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void GlView::resize_scene_buffer(int width, int height) {
  if (scene_fbo_ == 0) {
    glGenFramebuffers(1, &scene_fbo_);
    glGenRenderbuffers(1, &scene_color_);
    glGenRenderbuffers(1, &scene_depth_);
  }
  glBindRenderbuffer(GL_RENDERBUFFER, scene_color_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, scene_depth_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, 0);
  glBindFramebuffer(GL_FRAMEBUFFER, scene_fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, scene_color_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, scene_depth_);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw Error(fmt::format("OpenGL: the offscreen buffer of {}x{} is incomplete (status {:#x})",
                            width, height, status));
  scene_w_ = width;
  scene_h_ = height;
}

void GlView::draw_scene(const ViewerState& state, int width, int height) {
  const Color& bg = state.look().background;
  glViewport(0, 0, width, height);
  glClearColor(encode_gamma(bg.x()), encode_gamma(bg.y()), encode_gamma(bg.z()), 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  if (state.mode() == Mode::kRaytrace) {
    draw_preview(state);
    return;
  }
  const View view =
      View::from_camera(state.camera(), state.surface().scene_radius(), width, height);
  double near = 0, far = 0;
  // The clip volume plus a margin for disks reaching past its boundary.
  depth_range(view, state.surface().bounds().center(), 1.2 * state.surface().scene_radius(), near,
              far);
  const Eigen::Matrix4f view_m = view_matrix(view);
  const Eigen::Matrix4f proj_m = projection_matrix(view, near, far);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  if (state.mode() == Mode::kFloaters)
    draw_floaters(state, view_m, proj_m, Eigen::Vector4f(0, 0, width, height));
  else
    draw_mesh(state, view_m, proj_m);
  draw_singular(state, view_m, proj_m);
  glDisable(GL_DEPTH_TEST);
  glBindVertexArray(0);
}

void GlView::set_shading(const Program& p, const ViewerState& state, const Eigen::Matrix4f& view,
                         const Eigen::Matrix4f& proj) {
  glUseProgram(p.id);
  glUniformMatrix4fv(p.view, 1, GL_FALSE, view.data());
  glUniformMatrix4fv(p.proj, 1, GL_FALSE, proj.data());
  glUniform4f(p.flat_color, 0, 0, 0, 0);
  glUniform1f(p.depth_bias, 0);
  const RenderOptions& look = state.look();
  // Lights in eye space, turned by the view matrix's rotation.
  std::vector<float> dirs, colors;
  const Eigen::Matrix3d rotation = view.block<3, 3>(0, 0).cast<double>();
  for (const PlacedLight& l : camera_lights(look.lights, rotation)) {
    if (static_cast<int>(dirs.size()) / 3 == kMaxLights) break;
    for (int k = 0; k < 3; ++k) {
      dirs.push_back(static_cast<float>(l.direction[k]));
      colors.push_back(static_cast<float>(l.color[k]));
    }
  }
  const GLsizei count = static_cast<GLsizei>(dirs.size() / 3);
  glUniform1i(p.light_count, count);
  if (count > 0) {
    glUniform3fv(p.light_dir, count, dirs.data());
    glUniform3fv(p.light_color, count, colors.data());
  }
  set_material(p.front_diffuse, p.front_params, look.front);
  set_material(p.back_diffuse, p.back_params, look.back);
}

void GlView::draw_preview(const ViewerState& state) {
  const auto frame = state.preview();
  if (!frame || frame->image.width < 1) return;
  glBindTexture(GL_TEXTURE_2D, image_texture_);
  if (frame != uploaded_preview_) {
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, frame->image.width, frame->image.height, 0, GL_RGB,
                 GL_UNSIGNED_BYTE, frame->image.rgb.data());
    uploaded_preview_ = frame;
  }
  glUseProgram(image_.id);
  glActiveTexture(GL_TEXTURE0);
  glUniform1i(image_.image, 0);
  glBindVertexArray(image_vao_);
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

void GlView::draw_floaters(const ViewerState& state, const Eigen::Matrix4f& view,
                           const Eigen::Matrix4f& proj, const Eigen::Vector4f& viewport) {
  const auto frame = state.floaters();
  if (!frame) return;
  if (frame != uploaded_floaters_) {
    const size_t n = frame->positions.size();
    std::vector<float> data(n * kFloaterFloats);
    for (size_t i = 0; i < n; ++i) {
      float* d = &data[i * kFloaterFloats];
      for (int k = 0; k < 3; ++k) {
        d[k] = static_cast<float>(frame->positions[i][k]);
        d[3 + k] = static_cast<float>(frame->normals[i][k]);
      }
      d[6] = static_cast<float>(frame->radii[i]);
    }
    glBindBuffer(GL_ARRAY_BUFFER, floater_vbo_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data(),
                 GL_STREAM_DRAW);
    floater_count_ = static_cast<GLsizei>(n);
    uploaded_floaters_ = frame;
  }
  if (floater_count_ == 0) return;
  const DisplaySettings& display = state.display();
  if (display.draw_points) {
    set_shading(points_, state, view, proj);
    glUniform1f(points_.point_size, static_cast<float>(display.point_size_px));
  } else {
    set_shading(disks_, state, view, proj);
    glUniform1f(disks_.scale, static_cast<float>(display.disk_scale));
    glUniform4fv(disks_.viewport, 1, viewport.data());
  }
  glEnable(GL_PROGRAM_POINT_SIZE);
  glBindVertexArray(floater_vao_);
  glDrawArrays(GL_POINTS, 0, floater_count_);
  glDisable(GL_PROGRAM_POINT_SIZE);
}

void GlView::draw_mesh(const ViewerState& state, const Eigen::Matrix4f& view,
                       const Eigen::Matrix4f& proj) {
  const auto frame = state.mesh();
  if (!frame) return;
  glBindVertexArray(mesh_vao_);
  if (frame != uploaded_mesh_) {
    const Mesh& m = frame->mesh;
    const bool has_normals = m.normals.size() == m.positions.size();
    std::vector<float> vertices(m.positions.size() * 6);
    for (size_t i = 0; i < m.positions.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        vertices[6 * i + k] = static_cast<float>(m.positions[i][k]);
        vertices[6 * i + 3 + k] = has_normals ? static_cast<float>(m.normals[i][k]) : 0.0f;
      }
    glBindBuffer(GL_ARRAY_BUFFER, mesh_vbo_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)),
                 vertices.data(), GL_STREAM_DRAW);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                 static_cast<GLsizeiptr>(m.triangles.size() * 3 * sizeof(std::uint32_t)),
                 m.triangles.data(), GL_STREAM_DRAW);
    mesh_index_count_ = static_cast<GLsizei>(m.triangles.size() * 3);
    uploaded_mesh_ = frame;
  }
  if (mesh_index_count_ == 0) return;
  set_shading(mesh_, state, view, proj);
  const bool wireframe = state.display().wireframe;
  if (wireframe) {
    // Push the faces back a little so the edges drawn on top win the depth test.
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.0f, 1.0f);
  }
  glDrawElements(GL_TRIANGLES, mesh_index_count_, GL_UNSIGNED_INT, nullptr);
  if (wireframe) {
    glDisable(GL_POLYGON_OFFSET_FILL);
    glUniform4fv(mesh_.flat_color, 1, kWireColor);
    glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    glDrawElements(GL_TRIANGLES, mesh_index_count_, GL_UNSIGNED_INT, nullptr);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  }
}

void GlView::draw_singular(const ViewerState& state, const Eigen::Matrix4f& view,
                           const Eigen::Matrix4f& proj) {
  const auto frame = state.singular();
  if (!frame) return;
  // The tubes' and spheres' sizes and colours are the CPU overlay's.
  const SingularOverlay style;
  const double radius = state.surface().scene_radius();
  glBindVertexArray(singular_vao_);
  if (frame != uploaded_singular_ || radius != uploaded_singular_radius_) {
    const OverlayGeometry g = singular_overlay_geometry(frame->set, style, radius);
    glBindBuffer(GL_ARRAY_BUFFER, singular_vbo_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(g.vertices.size() * sizeof(float)),
                 g.vertices.data(), GL_STATIC_DRAW);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                 static_cast<GLsizeiptr>(g.indices.size() * sizeof(std::uint32_t)),
                 g.indices.data(), GL_STATIC_DRAW);
    singular_batches_ = g.batches;
    uploaded_singular_ = frame;
    uploaded_singular_radius_ = radius;
  }
  if (singular_batches_.empty()) return;
  set_shading(mesh_, state, view, proj);
  // The set lies on F = 0, but the mesh and the disks only approximate it: near a singular
  // curve marching cubes is off by up to about a cell, and a disk leaves the surface by up to
  // its radius. The overlay is depth tested with that much tolerance, so such errors do not
  // hide it while sheets farther in front still do.
  double tolerance = 0;
  if (state.mode() == Mode::kMesh) {
    tolerance = state.surface().bounds().size().maxCoeff() / state.mesh_settings().cells;
  } else if (const auto floaters = state.floaters()) {
    tolerance = floaters->nominal_radius * state.display().disk_scale;
  }
  glUniform1f(mesh_.depth_bias, static_cast<float>(tolerance));
  for (const OverlayGeometry::Batch& b : singular_batches_) {
    const Material m{.diffuse = b.color,
                     .ambient = style.ambient,
                     .specular = style.specular,
                     .shininess = style.shininess};
    set_material(mesh_.front_diffuse, mesh_.front_params, m);
    set_material(mesh_.back_diffuse, mesh_.back_params, m);
    glDrawElements(
        GL_TRIANGLES, static_cast<GLsizei>(b.count), GL_UNSIGNED_INT,
        reinterpret_cast<void*>(static_cast<std::uintptr_t>(b.first) * sizeof(std::uint32_t)));
  }
}

}  // namespace zeroset::viewer
