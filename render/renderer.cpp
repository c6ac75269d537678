#include "render/renderer.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/fixtures.hpp"
#include "render/gl_context.hpp"

namespace reposetwin::render {
namespace {

// ---------------------------------------------------------------------------------------------
// Shaders. Camera frame: x right, y down, z forward. Pixel (u, v) has its centre at integer
// coordinates; the GL window coordinate of pixel centre (u, v) is (u + 0.5, v + 0.5), i.e. the
// framebuffer's row 0 is the image's top row, so glReadPixels gives rows top first.
// u_f: focal length [px] or pixels per metre; u_c: principal point [px]; u_size: canvas [px];
// u_depth: (A, B) with ndc_z = A + B / z (perspective) or A z + B (orthographic).

constexpr const char* kCommon = R"(#version 450 core
uniform int u_ortho;
uniform float u_f;
uniform vec2 u_c;
uniform vec2 u_size;
uniform vec2 u_depth;
uniform vec3 u_light;
uniform float u_ambient;
uniform float u_diffuse;
vec2 pixel_to_ndc(vec2 pix) { return 2.0 * (pix + 0.5) / u_size - 1.0; }
)";

constexpr const char* kSphereVertex = R"(
layout(location = 0) in vec4 a_sphere;  // centre (camera frame) [m], radius [m]
layout(location = 1) in vec3 a_color;
flat out vec4 v_sphere;
flat out vec3 v_color;
void main() {
  vec3 c = a_sphere.xyz;
  float r = a_sphere.w;
  vec2 lo, hi;
  if (u_ortho == 1) {
    lo = u_c + u_f * (c.xy - r);
    hi = u_c + u_f * (c.xy + r);
  } else {
    // Planes through the eye tangent to the sphere bound x/z and y/z exactly.
    float d = c.z * c.z - r * r;
    vec2 q = sqrt(c.xy * c.xy + vec2(d));
    lo = u_c + u_f * (c.xy * c.z - r * q) / d;
    hi = u_c + u_f * (c.xy * c.z + r * q) / d;
  }
  lo -= 1.0;
  hi += 1.0;
  vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1));
  gl_Position = vec4(pixel_to_ndc(mix(lo, hi, corner)), 0.0, 1.0);
  v_sphere = a_sphere;
  v_color = a_color;
}
)";

constexpr const char* kSphereFragment = R"(
flat in vec4 v_sphere;
flat in vec3 v_color;
out vec4 o_color;
void main() {
  vec2 n = (gl_FragCoord.xy - 0.5 - u_c) / u_f;
  vec3 o = vec3(0.0);
  vec3 d = vec3(0.0, 0.0, 1.0);
  if (u_ortho == 1) {
    o = vec3(n, 0.0);
  } else {
    d = normalize(vec3(n, 1.0));
  }
  vec3 oc = v_sphere.xyz - o;
  float r = v_sphere.w;
  float b = dot(oc, d);
  vec3 p = oc - b * d;          // from the ray's closest point to the centre
  float h2 = r * r - dot(p, p);
  if (h2 < 0.0) discard;
  float s = sqrt(h2);
  float z = (o + (b - s) * d).z;
  vec3 normal = -(p + s * d) / r;  // hit - centre, free of cancellation
  float ndc = (u_ortho == 1) ? u_depth.x * z + u_depth.y : u_depth.x + u_depth.y / z;
  gl_FragDepth = 0.5 * ndc + 0.5;
  float light = u_ambient + u_diffuse * max(dot(normal, u_light), 0.0);
  o_color = vec4(v_color * light, 1.0);
}
)";

constexpr const char* kMeshVertex = R"(
layout(location = 0) in vec3 a_position;  // camera frame [m]
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_color;     // rgb, a = 1 when lit
out vec3 v_position;
out vec3 v_normal;
out vec4 v_color;
void main() {
  vec3 p = a_position;
  vec2 k = 2.0 * (u_c + 0.5) / u_size - 1.0;
  vec2 s = 2.0 * u_f / u_size;
  if (u_ortho == 1) {
    gl_Position = vec4(s * p.xy + k, u_depth.x * p.z + u_depth.y, 1.0);
  } else {
    gl_Position = vec4(s * p.xy + k * p.z, u_depth.x * p.z + u_depth.y, p.z);
  }
  v_position = p;
  v_normal = a_normal;
  v_color = a_color;
}
)";

constexpr const char* kMeshFragment = R"(
in vec3 v_position;
in vec3 v_normal;
in vec4 v_color;
out vec4 o_color;
void main() {
  if (v_color.a < 0.5) {
    o_color = vec4(v_color.rgb, 1.0);
    return;
  }
  vec3 view = (u_ortho == 1) ? vec3(0.0, 0.0, 1.0) : normalize(v_position);
  vec3 normal = normalize(v_normal);
  if (dot(normal, view) > 0.0) normal = -normal;  // two-sided: light the side we see
  float light = u_ambient + u_diffuse * max(dot(normal, u_light), 0.0);
  o_color = vec4(v_color.rgb * light, 1.0);
}
)";

GLuint compile(GLenum type, const char* body) {
  const GLuint shader = glCreateShader(type);
  const char* sources[2] = {kCommon, body};
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

// ---------------------------------------------------------------------------------------------
// Colours.

// SplitMix64: a counter-based hash, so particle i's tint depends only on (seed, i).
std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Distinct colours for materials (Okabe-Ito palette, readable by colour-blind readers).
constexpr std::array<Rgb, 8> kMaterialPalette = {{{230, 159, 0},
                                                  {86, 180, 233},
                                                  {0, 158, 115},
                                                  {240, 228, 66},
                                                  {0, 114, 178},
                                                  {213, 94, 0},
                                                  {204, 121, 167},
                                                  {120, 115, 108}}};

std::vector<std::array<float, 3>> sphere_colors(const Scene& scene, const RenderOptions& options) {
  const std::size_t n = scene.positions.size();
  std::vector<std::array<float, 3>> colors(n);
  auto to_float = [](Rgb c) {
    return std::array<float, 3>{c.r / 255.0f, c.g / 255.0f, c.b / 255.0f};
  };
  switch (options.shading) {
    case Shading::kPhoto: {
      const std::array<float, 3> base = to_float(options.particle_color);
      const std::uint64_t seed_hash = splitmix64(options.tint_seed);
      for (std::size_t i = 0; i < n; ++i) {
        const double u = static_cast<double>(splitmix64(seed_hash ^ i) >> 11) * 0x1.0p-53;
        const float k = static_cast<float>(1.0 + options.tint_fraction * (2.0 * u - 1.0));
        for (int c = 0; c < 3; ++c) colors[i][c] = std::min(base[c] * k, 1.0f);
      }
      break;
    }
    case Shading::kBySize: {
      const auto [lo, hi] = std::minmax_element(scene.radii.begin(), scene.radii.end());
      cv::Mat ramp(256, 1, CV_8UC1);
      for (int i = 0; i < 256; ++i) ramp.at<std::uint8_t>(i) = static_cast<std::uint8_t>(i);
      cv::Mat lut;
      cv::applyColorMap(ramp, lut, cv::COLORMAP_VIRIDIS);  // BGR
      const double span = *hi - *lo;
      for (std::size_t i = 0; i < n; ++i) {
        const double t = span > 0.0 ? (scene.radii[i] - *lo) / span : 0.5;
        const cv::Vec3b bgr = lut.at<cv::Vec3b>(static_cast<int>(std::lround(255.0 * t)));
        colors[i] = to_float(Rgb{bgr[2], bgr[1], bgr[0]});
      }
      break;
    }
    case Shading::kByMaterial:
      for (std::size_t i = 0; i < n; ++i) {
        const int m = scene.material_ids.empty() ? 0 : scene.material_ids[i];
        colors[i] =
            to_float(kMaterialPalette[static_cast<std::size_t>(m) % kMaterialPalette.size()]);
      }
      break;
  }
  return colors;
}

// ---------------------------------------------------------------------------------------------
// Distortion: the undistorted canvas and the maps from output pixels to canvas pixels.

struct Canvas {
  int width = 0;
  int height = 0;
  double cx = 0.0;  // principal point on the canvas [px]
  double cy = 0.0;
  cv::Mat map_u;  // (H x W) CV_32F: canvas u for each output pixel; empty without distortion
  cv::Mat map_v;
};

Canvas make_canvas(const camera::Camera& cam) {
  Canvas c;
  const int w = cam.intrinsics.width_px;
  const int h = cam.intrinsics.height_px;
  const double f = camera::focal_px(cam);
  const double cx = camera::principal_u(cam);
  const double cy = camera::principal_v(cam);
  if (cam.intrinsics.k1 == 0.0 && cam.intrinsics.k2 == 0.0) {
    c.width = w;
    c.height = h;
    c.cx = cx;
    c.cy = cy;
    return c;
  }
  std::vector<double> us(static_cast<std::size_t>(w) * h), vs(us.size());
  double u_lo = std::numeric_limits<double>::infinity(), u_hi = -u_lo, v_lo = u_lo, v_hi = -u_lo;
  double worst = 0.0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector2d xd((u - cx) / f, (v - cy) / f);
      const Eigen::Vector2d xu = camera::undistort_normalised(cam, xd);
      worst = std::max(worst, (camera::distort_normalised(cam, xu) - xd).norm() * f);
      const double cu = cx + f * xu.x(), cv_ = cy + f * xu.y();
      us[static_cast<std::size_t>(v) * w + u] = cu;
      vs[static_cast<std::size_t>(v) * w + u] = cv_;
      u_lo = std::min(u_lo, cu);
      u_hi = std::max(u_hi, cu);
      v_lo = std::min(v_lo, cv_);
      v_hi = std::max(v_hi, cv_);
    }
  }
  const std::string field = "camera.intrinsics.k1/k2 (" + std::to_string(cam.intrinsics.k1) + ", " +
                            std::to_string(cam.intrinsics.k2) + ")";
  if (!(worst < 1e-3) || !std::isfinite(u_lo + u_hi + v_lo + v_hi)) {
    throw std::invalid_argument("render: " + field +
                                " cannot be inverted over the image (the lens model folds)");
  }
  const double u0 = std::floor(u_lo) - 2.0, v0 = std::floor(v_lo) - 2.0;
  const double cw = std::ceil(u_hi) + 3.0 - u0, ch = std::ceil(v_hi) + 3.0 - v0;
  if (cw > std::min(4.0 * w, 16384.0) || ch > std::min(4.0 * h, 16384.0)) {
    throw std::invalid_argument("render: " + field +
                                " is too strong: the undistorted field would need a " +
                                std::to_string(cw) + " x " + std::to_string(ch) + " px canvas");
  }
  c.width = static_cast<int>(cw);
  c.height = static_cast<int>(ch);
  c.cx = cx - u0;
  c.cy = cy - v0;
  c.map_u.create(h, w, CV_32F);
  c.map_v.create(h, w, CV_32F);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      c.map_u.at<float>(v, u) = static_cast<float>(us[i] - u0);
      c.map_v.at<float>(v, u) = static_cast<float>(vs[i] - v0);
    }
  }
  return c;
}

// ---------------------------------------------------------------------------------------------
// Occlusion culling. Most spheres of a pile are buried: drawing them costs fragment work (the
// ray-cast depth defeats early depth tests) and changes no pixel. Per pixel we record the
// smallest "back" depth z + r of the spheres that certainly cover its centre: the ray through it
// hits such a sphere no deeper than that. The image of a sphere contains the disc of radius
// f r / z about its projected centre (the image of its cross-section facing the camera), shrunk
// here by a safety margin for the shader's float arithmetic. A sphere whose bounding box (with
// the drawn quad's margin) holds only pixels with a recorded depth clearly below its front
// z - r wins no depth test anywhere, so leaving it out gives the same bytes; a test checks that.

struct PixelBox {
  double u_lo, u_hi, v_lo, v_hi;
};

// The bounding box of a sphere's image on the canvas [px], as the vertex shader computes it.
PixelBox sphere_box(const Eigen::Vector3d& c, double r, double f, double cx, double cy,
                    bool ortho) {
  if (ortho) {
    return {cx + f * (c.x() - r), cx + f * (c.x() + r), cy + f * (c.y() - r), cy + f * (c.y() + r)};
  }
  const double d = c.z() * c.z() - r * r;
  const double qx = std::sqrt(c.x() * c.x() + d), qy = std::sqrt(c.y() * c.y() + d);
  return {cx + f * (c.x() * c.z() - r * qx) / d, cx + f * (c.x() * c.z() + r * qx) / d,
          cy + f * (c.y() * c.z() - r * qy) / d, cy + f * (c.y() * c.z() + r * qy) / d};
}

std::vector<char> visible_spheres(const std::vector<Eigen::Vector3d>& centres,
                                  const std::vector<double>& radii, const std::vector<char>& drawn,
                                  double f, double cx, double cy, bool ortho, int width, int height,
                                  double depth_range) {
  constexpr double kMarginPx = 0.02;     // inner disc shrink [px]
  constexpr double kDepthMargin = 1e-5;  // depth gap required to cull, relative to the larger
                                         // of the sphere's depth and the depth range [-]
  std::vector<float> occluder(static_cast<std::size_t>(width) * height,
                              std::numeric_limits<float>::infinity());
  const std::size_t n = centres.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!drawn[i]) continue;
    const Eigen::Vector3d& c = centres[i];
    const double scale = ortho ? f : f / c.z();
    const double u0 = cx + scale * c.x(), v0 = cy + scale * c.y();
    const double rho = scale * radii[i] * (1.0 - 1e-4) - kMarginPx;
    if (rho <= 0.0) continue;
    // Rounded up, so a float compared below is never nearer than the true back depth.
    const float back = std::nextafter(static_cast<float>(c.z() + radii[i]),
                                      std::numeric_limits<float>::infinity());
    const int v_lo = std::max(static_cast<int>(std::ceil(v0 - rho)), 0);
    const int v_hi = std::min(static_cast<int>(std::floor(v0 + rho)), height - 1);
    for (int v = v_lo; v <= v_hi; ++v) {
      const double w = std::sqrt(std::max(rho * rho - (v - v0) * (v - v0), 0.0));
      const int u_lo = std::max(static_cast<int>(std::ceil(u0 - w)), 0);
      const int u_hi = std::min(static_cast<int>(std::floor(u0 + w)), width - 1);
      float* row = occluder.data() + static_cast<std::size_t>(v) * width;
      for (int u = u_lo; u <= u_hi; ++u) row[u] = std::min(row[u], back);
    }
  }
  std::vector<char> visible(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!drawn[i]) continue;
    const PixelBox b = sphere_box(centres[i], radii[i], f, cx, cy, ortho);
    const double front_exact = centres[i].z() - radii[i];
    const double front_d =
        front_exact - kDepthMargin * std::max(std::abs(front_exact), depth_range);
    const float front = static_cast<float>(front_d);
    // The drawn quad's one-pixel margin, plus one for rounding.
    const int u_lo = std::max(static_cast<int>(std::floor(b.u_lo - 2.0)), 0);
    const int u_hi = std::min(static_cast<int>(std::ceil(b.u_hi + 2.0)), width - 1);
    const int v_lo = std::max(static_cast<int>(std::floor(b.v_lo - 2.0)), 0);
    const int v_hi = std::min(static_cast<int>(std::ceil(b.v_hi + 2.0)), height - 1);
    bool hidden = u_lo <= u_hi && v_lo <= v_hi;  // off the canvas: leave it to the clipper
    for (int v = v_lo; v <= v_hi && hidden; ++v) {
      const float* row = occluder.data() + static_cast<std::size_t>(v) * width;
      for (int u = u_lo; u <= u_hi; ++u) {
        if (!(row[u] < front)) {
          hidden = false;
          break;
        }
      }
    }
    visible[i] = hidden ? 0 : 1;
  }
  return visible;
}

struct MeshVertex {
  float position[3];
  float normal[3];
  float color[4];
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
    sphere_program = link(kSphereVertex, kSphereFragment);
    mesh_program = link(kMeshVertex, kMeshFragment);

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
          {col.r / 255.0f, col.g / 255.0f, col.b / 255.0f, fixtures.lit[i] ? 1.0f : 0.0f}};
    }

    const auto t1 = std::chrono::steady_clock::now();
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

    if (!vertices.empty()) {
      set_uniforms(mesh_program, cam, canvas, near_z, far_z, options);
      glBindVertexArray(mesh_vao);
      glBindBuffer(GL_ARRAY_BUFFER, mesh_vbo);
      glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(MeshVertex)),
                   vertices.data(), GL_STREAM_DRAW);
      glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(vertices.size()));
    }
    if (!instances.empty()) {
      set_uniforms(sphere_program, cam, canvas, near_z, far_z, options);
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
        RenderProfile{seconds(t0, t1), seconds(t1, t2), seconds(t2, t3), 0.0, instances.size()};
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
