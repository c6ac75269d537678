#include "render/renderer.hpp"

#include <GL/glcorearb.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/fixtures.hpp"
#include "render/gl_context.hpp"
#include "render/prepare.hpp"
#include "render/shaders.hpp"
#include "render/shadow_map.hpp"

namespace reposetwin::render {
namespace {

using detail::Canvas;
using detail::make_canvas;
using detail::sphere_colors;
using detail::visible_spheres;


GLuint compile(GLenum type, const char* body) {
  const GLuint shader = glCreateShader(type);
  const char* sources[2] = {shaders::kCommon, body};
  glShaderSource(shader, 2, sources, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    std::array<char, 4096> log{};
    glGetShaderInfoLog(shader, static_cast<GLsizei>(log.size()), nullptr, log.data());
    glDeleteShader(shader);
    throw std::runtime_error(std::string("render: shader compilation failed: ") + log.data());
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
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    std::array<char, 4096> log{};
    glGetProgramInfoLog(program, static_cast<GLsizei>(log.size()), nullptr, log.data());
    glDeleteProgram(program);
    throw std::runtime_error(std::string("render: shader link failed: ") + log.data());
  }
  return program;
}

struct MeshVertex {
  float position[3];
  float normal[3];
  float color[4];
  float world[3];
};

struct SphereInstance {
  float sphere[4];
  float color[3];
};

}  // namespace

// ---------------------------------------------------------------------------------------------

struct Renderer::Impl {
  GlContext context;
  GLuint sphere_program = 0;
  GLuint mesh_program = 0;
  GLuint sphere_vao = 0, sphere_vbo = 0;
  GLuint mesh_vao = 0, mesh_vbo = 0;
  GLuint fbo = 0, color_rb = 0, depth_rb = 0;
  int fbo_width = 0, fbo_height = 0;
  GLuint shadow_fbo = 0, shadow_tex = 0;
  int shadow_size = 0;
  RenderProfile profile;
  // The last canvas and distortion maps, reused while the lens and resolution stay the same
  // (the maps cost one iterative undistortion per pixel).
  std::array<double, 7> canvas_key{};
  Canvas canvas_cache;

  const Canvas& canvas_for(const camera::Camera& cam) {
    const camera::Intrinsics& in = cam.intrinsics;
    const std::array<double, 7> key = {static_cast<double>(in.width_px),
                                       static_cast<double>(in.height_px),
                                       camera::focal_px(cam),
                                       camera::principal_u(cam),
                                       camera::principal_v(cam),
                                       in.k1,
                                       in.k2};
    if (canvas_cache.width == 0 || key != canvas_key) {
      canvas_cache = make_canvas(cam);
      canvas_key = key;
    }
    return canvas_cache;
  }

  Impl() {
    sphere_program = link(shaders::kSphereVertex, shaders::kSphereFragment);
    mesh_program = link(shaders::kMeshVertex, shaders::kMeshFragment);

    glGenVertexArrays(1, &sphere_vao);
    glGenBuffers(1, &sphere_vbo);
    glBindVertexArray(sphere_vao);
    glBindBuffer(GL_ARRAY_BUFFER, sphere_vbo);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, sizeof(SphereInstance),
                          reinterpret_cast<void*>(offsetof(SphereInstance, sphere)));
    glVertexAttribDivisor(0, 1);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(SphereInstance),
                          reinterpret_cast<void*>(offsetof(SphereInstance, color)));
    glVertexAttribDivisor(1, 1);

    glGenVertexArrays(1, &mesh_vao);
    glGenBuffers(1, &mesh_vbo);
    glBindVertexArray(mesh_vao);
    glBindBuffer(GL_ARRAY_BUFFER, mesh_vbo);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                          reinterpret_cast<void*>(offsetof(MeshVertex, position)));
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                          reinterpret_cast<void*>(offsetof(MeshVertex, normal)));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                          reinterpret_cast<void*>(offsetof(MeshVertex, color)));
    glEnableVertexAttribArray(3);
    glVertexAttribPointer(3, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                          reinterpret_cast<void*>(offsetof(MeshVertex, world)));
    glBindVertexArray(0);
    check("renderer set-up");
  }

  ~Impl() {
    try {
      context.make_current();
    } catch (const std::exception&) {
      return;  // the context is gone; its objects went with it
    }
    glDeleteRenderbuffers(1, &color_rb);
    glDeleteRenderbuffers(1, &depth_rb);
    glDeleteTextures(1, &shadow_tex);
    glDeleteFramebuffers(1, &shadow_fbo);
    glDeleteFramebuffers(1, &fbo);
    glDeleteBuffers(1, &sphere_vbo);
    glDeleteBuffers(1, &mesh_vbo);
    glDeleteVertexArrays(1, &sphere_vao);
    glDeleteVertexArrays(1, &mesh_vao);
    glDeleteProgram(sphere_program);
    glDeleteProgram(mesh_program);
  }

  static void check(const char* what) {
    const GLenum e = glGetError();
    if (e != GL_NO_ERROR)
      throw std::runtime_error(std::string("render: OpenGL error ") + std::to_string(e) +
                               " during " + what);
  }

  void ensure_framebuffer(int w, int h) {
    if (fbo != 0 && w == fbo_width && h == fbo_height) return;
    if (fbo == 0) {
      glGenFramebuffers(1, &fbo);
      glGenRenderbuffers(1, &color_rb);
      glGenRenderbuffers(1, &depth_rb);
    }
    glBindRenderbuffer(GL_RENDERBUFFER, color_rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    glBindRenderbuffer(GL_RENDERBUFFER, depth_rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_rb);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw std::runtime_error("render: offscreen framebuffer of " + std::to_string(w) + " x " +
                               std::to_string(h) + " px is incomplete");
    fbo_width = w;
    fbo_height = h;
  }

  void set_uniforms(GLuint program, const camera::Camera& cam, const Canvas& canvas, double near_z,
                    double far_z, const RenderOptions& options) {
    const bool ortho = cam.projection == camera::Projection::kOrthographic;
    double a, b;
    if (ortho) {
      a = 2.0 / (far_z - near_z);
      b = -(far_z + near_z) / (far_z - near_z);
    } else {
      a = (far_z + near_z) / (far_z - near_z);
      b = -2.0 * far_z * near_z / (far_z - near_z);
    }
    const Eigen::Vector3d light = options.light_direction_camera.normalized();
    glUseProgram(program);
    glUniform1i(glGetUniformLocation(program, "u_ortho"), ortho ? 1 : 0);
    glUniform1f(glGetUniformLocation(program, "u_f"), static_cast<float>(camera::focal_px(cam)));
    glUniform2f(glGetUniformLocation(program, "u_c"), static_cast<float>(canvas.cx),
                static_cast<float>(canvas.cy));
    glUniform2f(glGetUniformLocation(program, "u_size"), static_cast<float>(canvas.width),
                static_cast<float>(canvas.height));
    glUniform2f(glGetUniformLocation(program, "u_depth"), static_cast<float>(a),
                static_cast<float>(b));
    glUniform3f(glGetUniformLocation(program, "u_light"), static_cast<float>(light.x()),
                static_cast<float>(light.y()), static_cast<float>(light.z()));
    glUniform1f(glGetUniformLocation(program, "u_ambient"), static_cast<float>(options.ambient));
    glUniform1f(glGetUniformLocation(program, "u_diffuse"), static_cast<float>(options.diffuse));
  }

  // The shadow and board-grain uniforms of a main-pass program; `light` is null without shadows.
  void set_look_uniforms(GLuint program, const Scene& scene, const RenderOptions& options,
                         const LightFrame* light, double softness_m) {
    glUseProgram(program);
    glUniform1f(glGetUniformLocation(program, "u_texture"),
                static_cast<float>(scene.plate.texture));
    glUniform1f(glGetUniformLocation(program, "u_texture_scale"),
                static_cast<float>(scene.plate.texture_scale_m));
    glUniform1i(glGetUniformLocation(program, "u_shadows"), light ? 1 : 0);
    if (!light) return;
    const Eigen::Matrix4f m = light->to_light().cast<float>();
    // Eigen stores column-major, as GL expects without transposition.
    glUniformMatrix4fv(glGetUniformLocation(program, "u_to_light"), 1, GL_FALSE, m.data());
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, shadow_tex);
    glUniform1i(glGetUniformLocation(program, "u_shadow_map"), 0);
    glUniform1i(glGetUniformLocation(program, "u_map_size"), light->size);
    const double texel_m = 1.0 / light->f;
    glUniform1f(glGetUniformLocation(program, "u_shadow_radius"),
                static_cast<float>(softness_m * light->f));
    // Against a sphere shadowing itself: offset along the normal and a depth bias, each about
    // two texels plus half the penumbra (the taps reach that far over the curved surface).
    const double slack_m = 2.0 * texel_m + 0.5 * softness_m;
    glUniform1f(glGetUniformLocation(program, "u_shadow_offset"), static_cast<float>(slack_m));
    glUniform1f(glGetUniformLocation(program, "u_shadow_bias"),
                static_cast<float>(slack_m / (light->far_z - light->near_z)));
    glUniform1f(glGetUniformLocation(program, "u_shadow_strength"),
                static_cast<float>(options.shadow_strength));
  }

  // The light's depth map of the spheres (camera-frame centres): an orthographic view along the
  // light drawn by the sphere program into a depth texture.
  LightFrame draw_shadow_map(const std::vector<Eigen::Vector3d>& centres,
                             const std::vector<double>& radii, const RenderOptions& options,
                             int size) {
    const LightFrame light = frame_light(centres, radii, options.light_direction_camera, size);
    if (shadow_fbo == 0) {
      glGenFramebuffers(1, &shadow_fbo);
      glGenTextures(1, &shadow_tex);
    }
    if (shadow_size != size) {
      glBindTexture(GL_TEXTURE_2D, shadow_tex);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT32F, size, size, 0, GL_DEPTH_COMPONENT,
                   GL_FLOAT, nullptr);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_NONE);
      glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow_tex, 0);
      glDrawBuffer(GL_NONE);
      glReadBuffer(GL_NONE);
      if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw std::runtime_error("render: shadow map framebuffer of " + std::to_string(size) +
                                 " px is incomplete");
      shadow_size = size;
    }
    std::vector<SphereInstance> instances(centres.size());
    for (std::size_t i = 0; i < centres.size(); ++i) {
      const Eigen::Vector3d c = light.rotation * centres[i];
      instances[i] = {{static_cast<float>(c.x()), static_cast<float>(c.y()),
                       static_cast<float>(c.z()), static_cast<float>(radii[i])},
                      {0.0f, 0.0f, 0.0f}};
    }
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
    glViewport(0, 0, size, size);
    glClearDepth(1.0);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glClear(GL_DEPTH_BUFFER_BIT);
    const double depth = light.far_z - light.near_z;
    glUseProgram(sphere_program);
    glUniform1i(glGetUniformLocation(sphere_program, "u_ortho"), 1);
    glUniform1i(glGetUniformLocation(sphere_program, "u_shadows"), 0);
    glUniform1f(glGetUniformLocation(sphere_program, "u_f"), static_cast<float>(light.f));
    glUniform2f(glGetUniformLocation(sphere_program, "u_c"), static_cast<float>(light.cx),
                static_cast<float>(light.cy));
    glUniform2f(glGetUniformLocation(sphere_program, "u_size"), static_cast<float>(size),
                static_cast<float>(size));
    glUniform2f(glGetUniformLocation(sphere_program, "u_depth"), static_cast<float>(2.0 / depth),
                static_cast<float>(-(light.far_z + light.near_z) / depth));
    glBindVertexArray(sphere_vao);
    glBindBuffer(GL_ARRAY_BUFFER, sphere_vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(instances.size() * sizeof(SphereInstance)),
                 instances.data(), GL_STREAM_DRAW);
    glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(instances.size()));
    glBindVertexArray(0);
    check("shadow map");
    return light;
  }

  // The backdrop paper: a quad just inside the far plane over the whole canvas, its colour
  // affine in the pixel position (so the two triangles interpolate it exactly), drawn first
  // without depth so everything else covers it.
  std::vector<MeshVertex> backdrop_quad(const Backdrop& bd, const camera::Camera& cam,
                                        const Canvas& canvas, double far_z) const {
    const bool ortho = cam.projection == camera::Projection::kOrthographic;
    const double f = camera::focal_px(cam);
    const double z = ortho ? far_z : 0.999 * far_z;
    const double w = canvas.width, h = canvas.height;
    auto corner = [&](double u, double v) {
      const double scale = ortho ? 1.0 / f : z / f;
      const double k = 1.0 + bd.gradient * (0.5 - 0.5 * (u / w + v / h));
      MeshVertex m{};
      m.position[0] = static_cast<float>((u - canvas.cx) * scale);
      m.position[1] = static_cast<float>((v - canvas.cy) * scale);
      m.position[2] = static_cast<float>(z);
      m.normal[2] = -1.0f;
      m.color[0] = static_cast<float>(std::min(bd.color.r * k / 255.0, 1.0));
      m.color[1] = static_cast<float>(std::min(bd.color.g * k / 255.0, 1.0));
      m.color[2] = static_cast<float>(std::min(bd.color.b * k / 255.0, 1.0));
      m.color[3] = 0.0f;
      return m;
    };
    const MeshVertex a = corner(-1.0, -1.0), b = corner(w + 1.0, -1.0), c = corner(w + 1.0, h + 1.0),
                     d = corner(-1.0, h + 1.0);
    return {a, b, c, a, c, d};
  }

  cv::Mat render(const Scene& scene, const camera::Camera& cam, const RenderOptions& options) {
    const auto t0 = std::chrono::steady_clock::now();
    validate(scene, cam, options);
    context.make_current();
    const Canvas& canvas = canvas_for(cam);
    const Eigen::Matrix3d rot = camera::rotation_world_to_camera(cam);
    const Eigen::Vector3d eye = cam.extrinsics.position;
    const bool ortho = cam.projection == camera::Projection::kOrthographic;

    // Spheres to the camera frame (double), then the depth range from everything drawn.
    const std::size_t n = scene.positions.size();
    std::vector<Eigen::Vector3d> centres(n);
    double sphere_front = std::numeric_limits<double>::infinity();  // nearest positive front
    double z_lo = std::numeric_limits<double>::infinity();          // nearest point of anything
    double far_z = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n; ++i) {
      centres[i] = rot * (scene.positions[i] - eye);
      const double front = centres[i].z() - scene.radii[i];
      if (front > 0.0) sphere_front = std::min(sphere_front, front);
      z_lo = std::min(z_lo, front);
      far_z = std::max(far_z, centres[i].z() + scene.radii[i]);
    }
    const TriangleMesh fixtures = build_fixtures(scene, cam, options.view);
    std::vector<Eigen::Vector3d> mesh_cam(fixtures.positions.size());
    double mesh_front = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < mesh_cam.size(); ++i) {
      mesh_cam[i] = rot * (fixtures.positions[i] - eye);
      if (mesh_cam[i].z() > 0.0) mesh_front = std::min(mesh_front, mesh_cam[i].z());
      z_lo = std::min(z_lo, mesh_cam[i].z());
      far_z = std::max(far_z, mesh_cam[i].z());
    }
    double near_z = 0.0;
    if (ortho) {
      // Depth is linear in z: the range simply covers everything, with a margin.
      const double pad = 0.01 * (far_z - z_lo) + 1e-6;
      near_z = z_lo - pad;
      far_z += pad;
    } else {
      if (!std::isfinite(sphere_front)) {
        throw std::invalid_argument(
            "render: camera.extrinsics.position sees no sphere in front of it");
      }
      // Depth precision goes as near / z^2: keep the near plane within 10x of the pile's front.
      // Fixture parts nearer than that (a plate corner beside the camera) are clipped.
      near_z = 0.5 * std::max(std::min(sphere_front, mesh_front), 0.1 * sphere_front);
      far_z = 1.01 * far_z + 1e-6;
    }

    std::vector<char> drawn(n, 1);
    for (std::size_t i = 0; i < n; ++i) {
      // Spheres beside or behind the camera (perspective) are not drawn.
      if (!ortho && centres[i].z() - scene.radii[i] <= near_z) drawn[i] = 0;
    }
    const std::vector<char> visible =
        !options.occlusion_culling
            ? drawn
            : visible_spheres(centres, scene.radii, drawn, camera::focal_px(cam), canvas.cx,
                              canvas.cy, ortho, canvas.width, canvas.height, far_z - near_z);
    std::vector<SphereInstance> instances;
    instances.reserve(n);
    const std::vector<std::array<float, 3>> colors = sphere_colors(scene, options);
    for (std::size_t i = 0; i < n; ++i) {
      if (!visible[i]) continue;
      const Eigen::Vector3d& c = centres[i];
      const double r = scene.radii[i];
      instances.push_back({{static_cast<float>(c.x()), static_cast<float>(c.y()),
                            static_cast<float>(c.z()), static_cast<float>(r)},
                           {colors[i][0], colors[i][1], colors[i][2]}});
    }
    std::vector<MeshVertex> vertices(mesh_cam.size());
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      const Eigen::Vector3d nrm = rot * fixtures.normals[i];
      const Rgb col = fixtures.colors[i];
      vertices[i] = {
          {static_cast<float>(mesh_cam[i].x()), static_cast<float>(mesh_cam[i].y()),
           static_cast<float>(mesh_cam[i].z())},
          {static_cast<float>(nrm.x()), static_cast<float>(nrm.y()), static_cast<float>(nrm.z())},
          {col.r / 255.0f, col.g / 255.0f, col.b / 255.0f, static_cast<float>(fixtures.lit[i])},
          {static_cast<float>(fixtures.positions[i].x()),
           static_cast<float>(fixtures.positions[i].y()),
           static_cast<float>(fixtures.positions[i].z())}};
    }

    const auto t1 = std::chrono::steady_clock::now();
    std::optional<LightFrame> light;
    int shadow_px = 0;
    double softness_m = options.shadow_softness_m;
    if (options.shadows) {
      if (softness_m == 0.0) {
        double sum = 0.0;
        for (const double r : scene.radii) sum += r;
        softness_m = 0.5 * sum / static_cast<double>(n);
      }
      shadow_px = shadow_map_side(options, canvas.width, canvas.height);
      light = draw_shadow_map(centres, scene.radii, options, shadow_px);
    }
    ensure_framebuffer(canvas.width, canvas.height);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, canvas.width, canvas.height);
    const Rgb bg = scene.backdrop.color;
    glClearColor(bg.r / 255.0f, bg.g / 255.0f, bg.b / 255.0f, 1.0f);
    glClearDepth(1.0);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);

    set_uniforms(mesh_program, cam, canvas, near_z, far_z, options);
    set_look_uniforms(mesh_program, scene, options, light ? &*light : nullptr, softness_m);
    if (scene.backdrop.gradient > 0.0) {
      const std::vector<MeshVertex> quad = backdrop_quad(scene.backdrop, cam, canvas, far_z);
      glDisable(GL_DEPTH_TEST);
      glDepthMask(GL_FALSE);
      glBindVertexArray(mesh_vao);
      glBindBuffer(GL_ARRAY_BUFFER, mesh_vbo);
      glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(quad.size() * sizeof(MeshVertex)),
                   quad.data(), GL_STREAM_DRAW);
      glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(quad.size()));
      glDepthMask(GL_TRUE);
      glEnable(GL_DEPTH_TEST);
    }
    if (!vertices.empty()) {
      glBindVertexArray(mesh_vao);
      glBindBuffer(GL_ARRAY_BUFFER, mesh_vbo);
      glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(MeshVertex)),
                   vertices.data(), GL_STREAM_DRAW);
      glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(vertices.size()));
    }
    if (!instances.empty()) {
      set_uniforms(sphere_program, cam, canvas, near_z, far_z, options);
      set_look_uniforms(sphere_program, scene, options, light ? &*light : nullptr, softness_m);
      glBindVertexArray(sphere_vao);
      glBindBuffer(GL_ARRAY_BUFFER, sphere_vbo);
      glBufferData(GL_ARRAY_BUFFER,
                   static_cast<GLsizeiptr>(instances.size() * sizeof(SphereInstance)),
                   instances.data(), GL_STREAM_DRAW);
      glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(instances.size()));
    }
    glBindVertexArray(0);
    glFinish();
    const auto t2 = std::chrono::steady_clock::now();

    cv::Mat image(canvas.height, canvas.width, CV_8UC3);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, canvas.width, canvas.height, GL_BGR, GL_UNSIGNED_BYTE, image.data);
    check("rendering");
    const auto t3 = std::chrono::steady_clock::now();
    auto seconds = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
    profile =
        RenderProfile{seconds(t0, t1), seconds(t1, t2), seconds(t2, t3), 0.0, instances.size(),
                      shadow_px};
    if (canvas.map_u.empty()) return image;
    cv::Mat out;
    cv::remap(image, out, canvas.map_u, canvas.map_v, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
              cv::Scalar(bg.b, bg.g, bg.r));
    profile.warp_s = seconds(t3, std::chrono::steady_clock::now());
    return out;
  }
};

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {}
Renderer::~Renderer() = default;

cv::Mat Renderer::render(const Scene& scene, const camera::Camera& cam,
                         const RenderOptions& options) {
  if (options.supersample == 1) return impl_->render(scene, cam, options);
  validate(scene, cam, options);
  // The same camera at s times the resolution: pixel centre u maps to s (u + 0.5) - 0.5, so the
  // s x s block averaged into output pixel u is centred on it and centroids stay put.
  const int s = options.supersample;
  camera::Camera fine = cam;
  fine.intrinsics.width_px = s * cam.intrinsics.width_px;
  fine.intrinsics.height_px = s * cam.intrinsics.height_px;
  fine.intrinsics.cx_px = s * (camera::principal_u(cam) + 0.5) - 0.5;
  fine.intrinsics.cy_px = s * (camera::principal_v(cam) + 0.5) - 0.5;
  RenderOptions o = options;
  o.supersample = 1;
  const cv::Mat big = impl_->render(scene, fine, o);
  cv::Mat out;
  cv::resize(big, out, cv::Size(cam.intrinsics.width_px, cam.intrinsics.height_px), 0.0, 0.0,
             cv::INTER_AREA);
  return out;
}

const RenderProfile& Renderer::last_profile() const { return impl_->profile; }

std::string Renderer::gl_description() const {
  return impl_->context.version() + " / " + impl_->context.renderer();
}

cv::Mat render_image(const Scene& scene, const camera::Camera& cam, const RenderOptions& options) {
  Renderer renderer;
  return renderer.render(scene, cam, options);
}

}  // namespace reposetwin::render
