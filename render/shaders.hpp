// shaders: the GLSL of the renderer (spheres ray-cast in quads, fixture meshes).
//
// Design note. Camera frame: x right, y down, z forward. Pixel (u, v) has its centre at integer
// coordinates; the GL window coordinate of pixel centre (u, v) is (u + 0.5, v + 0.5), i.e. the
// framebuffer's row 0 is the image's top row, so glReadPixels gives rows top first.
// u_f: focal length [px] or pixels per metre; u_c: principal point [px]; u_size: canvas [px];
// u_depth: (A, B) with ndc_z = A + B / z (perspective) or A z + B (orthographic).
//
// Shadows (u_shadows = 1): the shadow map holds, per texel, the depth [0, 1] towards the light
// of the nearest sphere (an orthographic view along the light, drawn by the sphere program
// itself with u_shadows = 0). u_to_light maps a camera-frame point to (texel u, texel v, depth).
// A fragment's lit fraction is the share of 16 fixed taps on a Vogel disc of u_shadow_radius
// texels that see no nearer sphere: a soft penumbra from integer texel fetches and fixed
// arithmetic only, so the same input gives the same bytes. The receiver is first moved along
// its normal (u_shadow_offset, camera-frame metres) and compared with a depth bias, against a
// sphere shadowing itself. A cleared texel (depth 1) is never a caster.
//
// Board grain (mesh vertices flagged 2): hashed value noise of the world position, three
// octaves, stretched along world x like a laminate's fibres, scaling the brightness by
// 1 + u_texture g with g in [-1, 1]. Integer hashing in GLSL is exact, so this is deterministic.
#pragma once

namespace reposetwin::render::shaders {

constexpr const char* kCommon = R"(#version 450 core
uniform int u_ortho;
uniform float u_f;
uniform vec2 u_c;
uniform vec2 u_size;
uniform vec2 u_depth;
uniform vec3 u_light;
uniform float u_ambient;
uniform float u_diffuse;
uniform int u_shadows;
uniform mat4 u_to_light;
uniform sampler2D u_shadow_map;
uniform int u_map_size;
uniform float u_shadow_radius;
uniform float u_shadow_offset;
uniform float u_shadow_bias;
uniform float u_shadow_strength;
vec2 pixel_to_ndc(vec2 pix) { return 2.0 * (pix + 0.5) / u_size - 1.0; }
float lit_fraction(vec3 p, vec3 n) {
  if (u_shadows == 0) return 1.0;
  vec3 q = (u_to_light * vec4(p + u_shadow_offset * n, 1.0)).xyz;
  float lit = 0.0;
  for (int k = 0; k < 16; ++k) {
    float r = u_shadow_radius * sqrt((float(k) + 0.5) / 16.0);
    float a = 2.39996323 * float(k);
    ivec2 t = ivec2(floor(q.xy + r * vec2(cos(a), sin(a)) + 0.5));
    if (t.x < 0 || t.y < 0 || t.x >= u_map_size || t.y >= u_map_size) {
      lit += 1.0;
      continue;
    }
    float d = texelFetch(u_shadow_map, t, 0).r;
    lit += (d >= 1.0 || q.z - u_shadow_bias <= d) ? 1.0 : 0.0;
  }
  return lit / 16.0;
}
float shade(vec3 p, vec3 normal) {
  float direct = max(dot(normal, u_light), 0.0);
  if (direct > 0.0) direct *= 1.0 - u_shadow_strength * (1.0 - lit_fraction(p, normal));
  return u_ambient + u_diffuse * direct;
}
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
  vec3 hit = o + (b - s) * d;
  float z = hit.z;
  vec3 normal = -(p + s * d) / r;  // hit - centre, free of cancellation
  float ndc = (u_ortho == 1) ? u_depth.x * z + u_depth.y : u_depth.x + u_depth.y / z;
  gl_FragDepth = 0.5 * ndc + 0.5;
  o_color = vec4(v_color * shade(hit, normal), 1.0);
}
)";

constexpr const char* kMeshVertex = R"(
layout(location = 0) in vec3 a_position;  // camera frame [m]
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_color;     // rgb, a = 0 unlit, 1 lit, 2 lit with board grain
layout(location = 3) in vec3 a_world;     // world frame [m] (board grain)
out vec3 v_position;
out vec3 v_normal;
out vec4 v_color;
out vec3 v_world;
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
  v_world = a_world;
}
)";

constexpr const char* kMeshFragment = R"(
in vec3 v_position;
in vec3 v_normal;
in vec4 v_color;
in vec3 v_world;
out vec4 o_color;
uniform float u_texture;
uniform float u_texture_scale;
uint hash3(ivec3 c) {
  uvec3 v = uvec3(c) * uvec3(1664525u, 1013904223u, 2654435769u);
  uint h = v.x ^ (v.y * 747796405u) ^ (v.z * 2891336453u);
  h ^= h >> 16;
  h *= 2246822519u;
  h ^= h >> 13;
  h *= 3266489917u;
  h ^= h >> 16;
  return h;
}
float lattice(ivec3 c) { return float(hash3(c) >> 8) * (1.0 / 16777216.0); }
float value_noise(vec3 p) {
  vec3 i = floor(p);
  vec3 f = p - i;
  vec3 w = f * f * (3.0 - 2.0 * f);
  ivec3 c = ivec3(i);
  float x00 = mix(lattice(c), lattice(c + ivec3(1, 0, 0)), w.x);
  float x10 = mix(lattice(c + ivec3(0, 1, 0)), lattice(c + ivec3(1, 1, 0)), w.x);
  float x01 = mix(lattice(c + ivec3(0, 0, 1)), lattice(c + ivec3(1, 0, 1)), w.x);
  float x11 = mix(lattice(c + ivec3(0, 1, 1)), lattice(c + ivec3(1, 1, 1)), w.x);
  return mix(mix(x00, x10, w.y), mix(x01, x11, w.y), w.z);
}
float board_grain(vec3 world) {
  vec3 p = world / u_texture_scale * vec3(0.12, 1.0, 1.0);
  float g = 0.55 * value_noise(p) + 0.3 * value_noise(2.03 * p + 17.0) +
            0.15 * value_noise(4.07 * p + 31.0);
  return 2.0 * g - 1.0;
}
void main() {
  if (v_color.a < 0.5) {
    o_color = vec4(v_color.rgb, 1.0);
    return;
  }
  vec3 view = (u_ortho == 1) ? vec3(0.0, 0.0, 1.0) : normalize(v_position);
  vec3 normal = normalize(v_normal);
  if (dot(normal, view) > 0.0) normal = -normal;  // two-sided: light the side we see
  vec3 rgb = v_color.rgb;
  if (v_color.a > 1.5) rgb *= 1.0 + u_texture * board_grain(v_world);
  o_color = vec4(min(rgb * shade(v_position, normal), vec3(1.0)), 1.0);
}
)";

}  // namespace reposetwin::render::shaders
