// gl_context: an offscreen OpenGL 4.5 core context from OSMesa (Mesa's llvmpipe), no display.
//
// Design note. The renders must run on machines without a display server (CI, compute nodes), so
// the context comes from OSMesa, which draws on the CPU into memory. OSMesa wants a colour buffer
// of its own; we give it a 1 x 1 one and draw into framebuffer objects of any size instead, which
// is also what lets one context serve renders of different resolutions. The GL headers stay in
// the .cpp files of render/: this header and every other public header are GL-free, so no other
// module can come to depend on OpenGL.
#pragma once

#include <memory>
#include <string>

namespace reposetwin::render {

/// An OpenGL 4.5 core-profile context created with OSMesa and made current on construction.
/// One per thread; not copyable.
class GlContext {
 public:
  /// Creates the context and makes it current. Throws std::runtime_error when OSMesa cannot
  /// provide a 4.5 core context.
  GlContext();
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  /// Makes this context current on the calling thread (needed only when several exist).
  void make_current();

  /// The GL_VERSION string, for example "4.5 (Core Profile) Mesa 22.3.6".
  std::string version() const;

  /// The GL_RENDERER string, for example "llvmpipe (LLVM 15.0.6, 256 bits)".
  std::string renderer() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace reposetwin::render
