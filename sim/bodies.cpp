#include "sim/bodies.hpp"

#include <cassert>
#include <stdexcept>

namespace reposetwin::sim {

void Bodies::keep(const std::vector<char>& flags) {
  assert(flags.size() == size());
  std::vector<std::size_t> order;
  order.reserve(size());
  for (std::size_t b = 0; b < flags.size(); ++b)
    if (flags[b]) order.push_back(b);
#define REPOSETWIN_KEEP_BODY_FIELD(type, name, doc)                          \
  {                                                                          \
    HugeVector<type> tmp(order.size());                                      \
    for (std::size_t b = 0; b < order.size(); ++b) tmp[b] = name[order[b]];  \
    name.swap(tmp);                                                          \
  }
  REPOSETWIN_BODY_FIELDS(REPOSETWIN_KEEP_BODY_FIELD)
#undef REPOSETWIN_KEEP_BODY_FIELD
}

void Bodies::permute(const std::vector<std::int32_t>& order) {
  assert(order.size() == size());
#define REPOSETWIN_PERMUTE_BODY_FIELD(type, name, doc)                        \
  {                                                                           \
    HugeVector<type> tmp(order.size());                                       \
    for (std::size_t b = 0; b < order.size(); ++b) tmp[b] = name[order[b]];   \
    name.swap(tmp);                                                           \
  }
  REPOSETWIN_BODY_FIELDS(REPOSETWIN_PERMUTE_BODY_FIELD)
#undef REPOSETWIN_PERMUTE_BODY_FIELD
}

void index_body_components(const Particles& p, std::size_t bodies, BodyComponents& bc) {
  bc.start.assign(bodies + 1, 0);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::int32_t b = p.body[i];
    if (b < 0) continue;
    if (static_cast<std::size_t>(b) >= bodies)
      throw std::logic_error("index_body_components: a particle's body index is out of range");
    ++bc.start[b + 1];
  }
  for (std::size_t b = 0; b < bodies; ++b) bc.start[b + 1] += bc.start[b];
  bc.particle.assign(bc.start[bodies], -1);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::int32_t b = p.body[i];
    if (b < 0) continue;
    const std::int32_t c = p.component[i];
    if (c < 0 || c >= bc.start[b + 1] - bc.start[b] || bc.particle[bc.start[b] + c] >= 0)
      throw std::logic_error("index_body_components: a body's component indices are broken");
    bc.particle[bc.start[b] + c] = static_cast<std::int32_t>(i);
  }
}

}  // namespace reposetwin::sim
