#include "render/gl_context.hpp"

#include <GL/osmesa.h>

#include <array>
#include <stdexcept>

namespace reposetwin::render {

struct GlContext::Impl {
  OSMesaContext context = nullptr;
  std::array<unsigned char, 4> buffer{};  // the 1 x 1 RGBA buffer OSMesa insists on
};

GlContext::GlContext() : impl_(std::make_unique<Impl>()) {
  // Depth, stencil and accumulation live in our framebuffer objects, not in OSMesa's buffer.
  const int attribs[] = {OSMESA_FORMAT,
                         OSMESA_RGBA,
                         OSMESA_DEPTH_BITS,
                         0,
                         OSMESA_STENCIL_BITS,
                         0,
                         OSMESA_ACCUM_BITS,
                         0,
                         OSMESA_PROFILE,
                         OSMESA_CORE_PROFILE,
                         OSMESA_CONTEXT_MAJOR_VERSION,
                         4,
                         OSMESA_CONTEXT_MINOR_VERSION,
                         5,
                         0};
  impl_->context = OSMesaCreateContextAttribs(attribs, nullptr);
  if (impl_->context == nullptr) {
    throw std::runtime_error(
        "render: OSMesa could not create an OpenGL 4.5 core context (is Mesa's llvmpipe "
        "installed?)");
  }
  make_current();
}

GlContext::~GlContext() {
  if (impl_ && impl_->context != nullptr) OSMesaDestroyContext(impl_->context);
}

void GlContext::make_current() {
  if (!OSMesaMakeCurrent(impl_->context, impl_->buffer.data(), GL_UNSIGNED_BYTE, 1, 1)) {
    throw std::runtime_error("render: OSMesaMakeCurrent failed");
  }
}

std::string GlContext::version() const {
  const GLubyte* s = glGetString(GL_VERSION);
  return s ? reinterpret_cast<const char*>(s) : "";
}

std::string GlContext::renderer() const {
  const GLubyte* s = glGetString(GL_RENDERER);
  return s ? reinterpret_cast<const char*>(s) : "";
}

}  // namespace reposetwin::render
