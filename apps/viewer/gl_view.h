#pragma once
// The OpenGL 3.3 core drawing of the viewer's 3D view: the ray-traced preview as a texture,
// floaters as disks oriented by their normals (or round points), and the mesh with
// smooth shading and an optional wireframe, with the singular set over them as tubes and
// spheres. Front and back sides are shaded with the two materials of the look (the back
// darker), exactly as the CPU renderer shades them.
#include <epoxy/gl.h>

#include <memory>
#include <vector>

#include "singular_geometry.h"
#include "viewer_state.h"

namespace zeroset::viewer {

/// GL resources and drawing. Needs a current OpenGL 3.3 core context for its whole life;
/// not thread-safe (the UI thread owns it). Uploads a frame's data only when the state hands
/// out a new frame.
class GlView {
 public:
  /// Compiles the shaders. Throws Error with the GL info log on failure.
  GlView();
  ~GlView();
  GlView(const GlView&) = delete;
  GlView& operator=(const GlView&) = delete;

  /// Draws the state's mode into the rectangle (x, y, width, height) of the default
  /// framebuffer (pixels, origin bottom-left). The scene is drawn offscreen when it changed
  /// and copied into place. Throws Error when the offscreen buffer cannot be made.
  void draw(const ViewerState& state, int x, int y, int width, int height);

 private:
  struct Program {
    GLuint id = 0;
    GLint view = -1, proj = -1, scale = -1, point_size = -1, viewport = -1, flat_color = -1;
    GLint light_count = -1, light_dir = -1, light_color = -1;
    GLint front_diffuse = -1, front_params = -1, back_diffuse = -1, back_params = -1;
    GLint image = -1, depth_bias = -1;
  };

  std::vector<double> scene_key(const ViewerState& state, int width, int height) const;
  void resize_scene_buffer(int width, int height);
  void draw_scene(const ViewerState& state, int width, int height);
  void draw_preview(const ViewerState& state);
  void draw_floaters(const ViewerState& state, const Eigen::Matrix4f& view,
                     const Eigen::Matrix4f& proj, const Eigen::Vector4f& viewport);
  void draw_mesh(const ViewerState& state, const Eigen::Matrix4f& view,
                 const Eigen::Matrix4f& proj);
  void draw_singular(const ViewerState& state, const Eigen::Matrix4f& view,
                     const Eigen::Matrix4f& proj);
  void set_shading(const Program& p, const ViewerState& state, const Eigen::Matrix4f& view,
                   const Eigen::Matrix4f& proj);

  Program disks_;   // point sprites cut to the ellipse each disk projects to
  Program points_;  // round point sprites of a fixed size
  Program mesh_;
  Program image_;  // a full-viewport textured triangle

  GLuint floater_vbo_ = 0, floater_vao_ = 0;
  GLsizei floater_count_ = 0;
  std::shared_ptr<const FloaterFrame> uploaded_floaters_;

  GLuint mesh_vao_ = 0, mesh_vbo_ = 0, mesh_ebo_ = 0;
  GLsizei mesh_index_count_ = 0;
  std::shared_ptr<const MeshFrame> uploaded_mesh_;

  GLuint singular_vao_ = 0, singular_vbo_ = 0, singular_ebo_ = 0;
  std::vector<OverlayGeometry::Batch> singular_batches_;
  std::shared_ptr<const SingularFrame> uploaded_singular_;
  double uploaded_singular_radius_ = 0;  // the scene radius its tubes were sized for

  GLuint image_vao_ = 0, image_texture_ = 0;
  std::shared_ptr<const PreviewFrame> uploaded_preview_;

  GLuint scene_fbo_ = 0, scene_color_ = 0, scene_depth_ = 0;  // the scene, drawn offscreen
  int scene_w_ = 0, scene_h_ = 0;
  std::vector<double> scene_key_;  // what the offscreen picture shows
};

}  // namespace zeroset::viewer
