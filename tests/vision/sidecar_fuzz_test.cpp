// Camera sidecar fuzz, by property: a render's side and top sidecars (fuzz/corpus/sidecar/),
// with every field in turn deleted or replaced by a hostile value (null, a string, a negative,
// zero, tiny, huge and overflowing numbers, NaN and Infinity as a careless writer prints them, a
// boolean, an empty array or object, a vector of the wrong length, a fraction for an integer),
// and the whole file truncated and byte-flipped at seeded places; each read as `reposetwin
// measure --camera` reads it (camera::read_sidecar for its view, then vision's
// scale_from_sidecar). The property, for every mutation:
//  - either it is refused with std::invalid_argument naming the file and the field mutated (a
//    byte-level corruption: the file), and no other exception type, no crash,
//  - or it is accepted, and then the file itself holds every field the projection uses (none
//    taken from a default camera), every value is finite (focal length in pixels positive, the
//    image size positive, the distortion within +-1, the principal point and the pose finite),
//    the camera projects its own look-at point to a finite pixel within one image size of the
//    image (a shift lens moves it off the image), and the
//    sidecar's scale (mm_per_px_at_axis, the marker band), when given, is finite and positive.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <typeinfo>
#include <vector>

#include "camera/camera.hpp"
#include "vision/measure.hpp"

namespace reposetwin {
namespace {
namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(REPOSETWIN_SOURCE_DIR) / "fuzz/corpus/sidecar";

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Every member's JSON pointer below the root (objects only; an array is one field).
void member_paths(const nlohmann::json& j, const nlohmann::json::json_pointer& at,
                  std::vector<nlohmann::json::json_pointer>& out) {
  if (!j.is_object()) return;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const auto p = at / it.key();
    out.push_back(p);
    member_paths(it.value(), p, out);
  }
}

// Replacements as raw JSON text: NaN and Infinity are not JSON, and 1e400 overflows a double.
const std::vector<std::string> kHostile = {
    "null", "\"junk\"", "-1", "0", "-0.0", "1e-300", "1e300", "1e400", "-1e400", "NaN",
    "Infinity", "true", "[]", "{}", "[1.0, 2.0]", "[\"a\", \"b\", \"c\"]", "[1e400, 0, 0]",
    "3.5", "99999999999", "18446744073709551616", "\"side\"", "\"top\"", "\"orthographic\""};

struct Outcome {
  bool accepted = false;
  std::string why;  // a broken property; empty when it holds
};

// The property for one sidecar text written to `file`. `field` is what a refusal must name
// (empty: only the file).
std::string check(const fs::path& file, const std::string& text, camera::SidecarView view,
                  const std::string& field) {
  { std::ofstream(file, std::ios::binary | std::ios::trunc) << text; }
  const std::string path = file.string();
  std::optional<camera::Camera> cam;
  try {
    cam = camera::read_sidecar(path, view);
    (void)vision::scale_from_sidecar(path, view);
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    if (what.find(path) == std::string::npos) return "refused without the file: " + what;
    if (!field.empty() && what.find(field) == std::string::npos)
      return "refused without the field " + field + ": " + what;
    return "";
  } catch (const std::exception& e) {
    return std::string("another exception (") + typeid(e).name() + "): " + e.what();
  }
  // Accepted: the file holds every field the projection uses.
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("camera"))
    return "accepted without a camera object";
  const nlohmann::json& c = j["camera"];
  auto has = [&](const char* block, const char* key) {
    return c.contains(block) && c[block].is_object() && c[block].contains(key);
  };
  if (!c.contains("projection")) return "accepted without camera.projection";
  std::vector<std::pair<const char*, const char*>> need = {
      {"intrinsics", "width_px"}, {"intrinsics", "height_px"}, {"extrinsics", "position"},
      {"extrinsics", "look_at"},  {"extrinsics", "up"}};
  if (cam->projection == camera::Projection::kPerspective) {
    need.push_back({"intrinsics", "focal_length_mm"});
    need.push_back({"intrinsics", "sensor_width_mm"});
  } else {
    need.push_back({"intrinsics", "ortho_width_m"});
  }
  for (const auto& [block, key] : need)
    if (!has(block, key)) return std::string("accepted without ") + block + "." + key;
  const camera::Intrinsics& in = cam->intrinsics;
  const double f = camera::focal_px(*cam);
  if (!(std::isfinite(f) && f > 0)) return "accepted with focal length " + std::to_string(f) + " px";
  if (!(in.width_px > 0 && in.height_px > 0)) return "accepted with a non-positive image size";
  if (!(std::abs(in.k1) <= 1 && std::abs(in.k2) <= 1)) return "accepted with an absurd distortion";
  if ((in.cx_px && !std::isfinite(*in.cx_px)) || (in.cy_px && !std::isfinite(*in.cy_px)))
    return "accepted with a non-finite principal point";
  const camera::Extrinsics& ex = cam->extrinsics;
  if (!(ex.position.allFinite() && ex.look_at.allFinite() && ex.up.allFinite()))
    return "accepted with a non-finite pose";
  // The look-at point projects to the principal point, which a shift lens moves off the image
  // by less than the image's size (camera.cpp says why).
  const auto px = camera::project(*cam, ex.look_at);
  const double w = in.width_px, h = in.height_px;
  if (!px || !px->allFinite() || px->x() < -0.5 - w || px->x() > 2 * w - 0.5 ||
      px->y() < -0.5 - h || px->y() > 2 * h - 0.5)
    return "accepted, but its look-at point projects more than an image's size off the image";
  const vision::ScaleSpec s = vision::scale_from_sidecar(path, view);
  if (s.mm_per_px && !(std::isfinite(*s.mm_per_px) && *s.mm_per_px > 0))
    return "accepted with mm_per_px_at_axis " + std::to_string(*s.mm_per_px);
  if (!(std::isfinite(s.marker.band_mm) && s.marker.band_mm > 0))
    return "accepted with a marker band of " + std::to_string(s.marker.band_mm) + " mm";
  return "";
}

struct Case {
  std::string what;
  std::string text;
  std::string field;
};

// Every member deleted, every member replaced by every hostile value.
std::vector<Case> field_cases(const std::string& original) {
  const nlohmann::json base = nlohmann::json::parse(original);
  std::vector<nlohmann::json::json_pointer> paths;
  member_paths(base, nlohmann::json::json_pointer(), paths);
  std::vector<Case> out;
  for (const auto& p : paths) {
    const std::string field = p.back();
    nlohmann::json del = base;
    del[p.parent_pointer()].erase(field);
    out.push_back({"delete " + p.to_string(), del.dump(1), field});
    for (const std::string& v : kHostile) {
      nlohmann::json rep = base;
      rep[p] = "@@HOSTILE@@";
      std::string text = rep.dump(1);
      text.replace(text.find("\"@@HOSTILE@@\""), 13, v);
      // Not JSON any more (NaN, Infinity, 1e400): refused as a file, no field to name.
      const bool json = !nlohmann::json::parse(text, nullptr, false).is_discarded();
      out.push_back({p.to_string() + " = " + v, text, json ? field : ""});
    }
  }
  return out;
}

// The file truncated at seeded lengths and with seeded bytes flipped: refused naming the file,
// or still a complete sidecar.
std::vector<Case> byte_cases(const std::string& original, std::uint64_t seed, int count) {
  std::mt19937_64 rng(seed);
  std::vector<Case> out;
  for (int i = 0; i < count; ++i) {
    std::string t = original;
    if (i % 2 == 0) {
      t.resize(rng() % t.size());
      out.push_back({"truncated at " + std::to_string(t.size()), t, ""});
    } else {
      const std::size_t at = rng() % t.size();
      t[at] = static_cast<char>(rng() % 256);
      out.push_back({"byte " + std::to_string(at) + " changed", t, ""});
    }
  }
  return out;
}

void run_all(const std::string& name, camera::SidecarView view, std::size_t min_cases) {
  const std::string original = slurp(kCorpus / name);
  ASSERT_FALSE(original.empty());
  const fs::path dir = fs::temp_directory_path() / "reposetwin_sidecar_fuzz";
  fs::create_directories(dir);
  const fs::path file = dir / ("fuzz_" + name);
  ASSERT_EQ(check(file, original, view, ""), "") << "the unmutated sidecar";
  std::vector<Case> cases = field_cases(original);
  for (Case& c : byte_cases(original, 20261206, 400)) cases.push_back(std::move(c));
  ASSERT_GE(cases.size(), min_cases);
  int broken = 0;
  for (const Case& c : cases) {
    const std::string why = check(file, c.text, view, c.field);
    if (!why.empty() && ++broken <= 40) ADD_FAILURE() << name << ": " << c.what << ": " << why;
  }
  EXPECT_EQ(broken, 0) << "of " << cases.size() << " mutations";
}

TEST(SidecarFuzz, SideViewEveryFieldDeletedOrHostile) {
  run_all("side.json", camera::SidecarView::kSide, 1400);
}

TEST(SidecarFuzz, TopViewEveryFieldDeletedOrHostile) {
  run_all("top.json", camera::SidecarView::kTop, 1400);
}

// A shift lens moves the principal point off the image: the twin's own pitched cameras that keep
// the pile framed (loop-synth's camera case writes cy -58 px on a 720 px image) are read, and
// the loop then judges the photo against the declared pose. More than an image's size off is
// refused, naming the field and the value.
TEST(SidecarFuzz, APrincipalPointOffTheImageByLessThanItsSizeIsRead) {
  nlohmann::json j = nlohmann::json::parse(slurp(kCorpus / "side.json"));
  const int h = j["camera"]["intrinsics"]["height_px"].get<int>();
  const fs::path file = fs::temp_directory_path() / "reposetwin_sidecar_shift.json";
  j["camera"]["intrinsics"]["cy_px"] = -0.08 * h;
  { std::ofstream(file, std::ios::trunc) << j.dump(); }
  EXPECT_NO_THROW((void)camera::read_sidecar(file.string(), camera::SidecarView::kSide));
  j["camera"]["intrinsics"]["cy_px"] = -1.2 * h;
  { std::ofstream(file, std::ios::trunc) << j.dump(); }
  try {
    (void)camera::read_sidecar(file.string(), camera::SidecarView::kSide);
    ADD_FAILURE() << "a principal point 1.2 image heights off the image was read";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("intrinsics.cy_px"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("within one image size"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace reposetwin
