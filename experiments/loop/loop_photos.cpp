// photo_pairs (loop_stages.hpp): for every test, the lab's photo (when it gave one) and one
// twin photo of the same test, each with vision's overlay, copied into OUT/photos/<id>/ for the
// page.
//
// Design note. The page reads loop.json and the files it names, and never simulates, so the
// loop keeps the pictures. The twin's is one pile the loop has already simulated: the first
// seed's pour at the grid point nearest the final mu_r, on the surface that weighs most in the
// final model (the baseline, or an effect's refit trial), so the pile run is found in the cache
// and only its photograph is new (one photo job per test, with the photos and overlays kept). It
// is photographed as every twin pile is (the lab's cameras when it gave them), and the view shown
// is the one through the lab photo's camera. A test with a typed angle still gets the twin's
// photo: it is what the twin's angle was read from (on the paper's Table 1, the flat top that
// keeps the sphere piles' atan(2H/D) low), and a reader checks a measurement by looking at it.
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "experiments/loop/loop_stages.hpp"
#include "experiments/photos/photographs.hpp"

namespace reposetwin::experiments::loop_detail {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The surface with the largest weight in the model.
const Surface& heaviest(const Model& model) {
  std::size_t best = 0;
  for (std::size_t k = 1; k < model.terms.size(); ++k)
    if (model.terms[k].first > model.terms[best].first) best = k;
  return *model.terms.at(best).second;
}

std::size_t nearest(const std::vector<double>& grid, double mu) {
  std::size_t j = 0;
  for (std::size_t k = 1; k < grid.size(); ++k)
    if (std::abs(grid[k] - mu) < std::abs(grid[j] - mu)) j = k;
  return j;
}

// The lab's first photo vision measures, with its overlay written and the photo copied into
// `dir`; `camera` receives the index of its camera in test.cameras (0 without cameras).
PhotoView lab_view(const LabTest& test, const std::string& data_file, const fs::path& out,
                   const fs::path& rel, std::size_t& camera) {
  const std::string where =
      data_file + " line " + std::to_string(test.line) + " (test " + test.id + ")";
  std::string last_error;
  for (const std::string& photo : test.photos) {
    LabPhotoMeasurement m;
    try {
      m = measure_lab_photos({photo}, test.photo_scale,
                             {where + ", column photo", where + ", column photo_camera",
                              where + ", column mm_per_px", "photo_camera", "mm_per_px"},
                             true);
    } catch (const std::exception& e) {
      last_error = e.what();  // recorded as unmeasured when the CSV was read; try the next
      continue;
    }
    const std::string name = "lab" + fs::path(photo).extension().string();
    fs::copy_file(photo, out / rel / name, fs::copy_options::overwrite_existing);
    const cv::Mat& overlay = m.overlays.at(0);
    write_image_atomic((out / rel / "lab.measured.png").string(), overlay);
    camera = 0;
    if (!m.cameras.empty())
      for (std::size_t k = 0; k < test.cameras.size(); ++k)
        if (camera::to_json(test.cameras[k]) == camera::to_json(m.cameras[0])) camera = k;
    const json& v = m.record.at("views").at(0);
    return {(rel / name).string(),
            (rel / "lab.measured.png").string(),
            photo,
            v.at("scale").at("mm_per_px").get<double>(),
            overlay.cols,
            overlay.rows,
            v.at("theta_deg").get<double>()};
  }
  throw std::runtime_error(where + ": none of its photos could be measured again for the page (" +
                           last_error + ")");
}

// The twin's view through camera `camera` (or the first measured one), copied into `dir`; none,
// with `why` set, when no view of the photograph was measured or its files are gone (a cache
// carried to another machine by scripts/collect_results.sh keeps result.json, not the PNGs).
std::optional<PhotoView> twin_view(const SimOutcome& o, std::size_t camera, const fs::path& out,
                                   const fs::path& rel, std::string& why) {
  const json* pick = nullptr;
  if (o.views.is_array())
    for (std::size_t k = 0; k < o.views.size(); ++k) {
      const json& v = o.views[k];
      if (!v.contains("overlay")) continue;
      if (pick == nullptr || k == camera) pick = &v;
      if (k == camera) break;
    }
  if (pick == nullptr) {
    why = o.no_pile.empty() ? "the twin's pile was not photographed (" + o.sim_dir + ")"
                            : "no view of the twin's photograph could be measured: " + o.no_pile;
    return std::nullopt;
  }
  const fs::path dir(o.image_dir);
  const fs::path photo = dir / pick->at("photo").get<std::string>();
  const fs::path overlay = dir / pick->at("overlay").get<std::string>();
  for (const fs::path& f : {photo, overlay})
    if (!fs::is_regular_file(f)) {
      why = "the twin's photograph is recorded in the cache but " + f.filename().string() +
            " is not there (a cache collected without images); delete the cache's cases/" +
            (dir.parent_path().filename() / dir.filename()).string() +
            " and run the loop again to photograph it anew";
      return std::nullopt;
    }
  fs::copy_file(photo, out / rel / "twin.png", fs::copy_options::overwrite_existing);
  fs::copy_file(overlay, out / rel / "twin.measured.png", fs::copy_options::overwrite_existing);
  const cv::Mat img = cv::imread(overlay.string(), cv::IMREAD_UNCHANGED);
  if (img.empty()) throw std::runtime_error(overlay.string() + ": cannot read the twin's overlay");
  return PhotoView{(rel / "twin.png").string(),
                   (rel / "twin.measured.png").string(),
                   photo.string(),
                   pick->at("scale").at("mm_per_px").get<double>(),
                   img.cols,
                   img.rows,
                   pick->at("theta_deg").get<double>()};
}

// The page's photographs, one request per pair. A photograph that cannot be taken must not
// lose the loop's finished work: a cache carried to another machine by
// scripts/collect_results.sh has the piles' result.json but not their particles (final.vtp),
// so a photo not taken before cannot be taken there. Then each is asked for alone (the ones
// taken come from the cache) and a request without one gets the reason in `notes`.
std::vector<std::optional<SimOutcome>> photograph_for_page(
    PileStore& store, const std::vector<SimRequest>& requests, std::vector<std::string>& notes) {
  std::vector<std::optional<SimOutcome>> out(requests.size());
  try {
    const std::vector<SimOutcome> all = store.cache.run(requests);
    for (std::size_t k = 0; k < all.size(); ++k) out[k] = all[k];
    return out;
  } catch (const std::exception&) {
  }
  for (std::size_t k = 0; k < requests.size(); ++k) {
    try {
      out[k] = store.cache.run({requests[k]}).at(0);
    } catch (const std::exception& e) {
      const std::string what = e.what();
      notes[k] =
          what.find("final.vtp") != std::string::npos
              ? "the twin's pile could not be photographed for the page: its particles "
                "(final.vtp) are not in the cache, as in a cache collected by "
                "scripts/collect_results.sh (the loop's measurements of it are unaffected)"
              : "the twin's pile could not be photographed for the page: " + what.substr(0, 300);
    }
  }
  return out;
}

}  // namespace

std::vector<PhotoPair> photo_pairs(const LoopContext& ctx, PileStore& store,
                                   const LoopState& state) {
  const LoopSettings& s = ctx.s();
  const fs::path dir(ctx.out);
  std::vector<PhotoPair> pairs;
  std::vector<std::size_t> cameras;
  std::vector<SimRequest> requests;
  std::vector<std::size_t> asked;  // the pair of each request: a test predicted no pile has none
  const Surface& surf = heaviest(state.model);
  ImageVariant image = s.image;
  image.keep_photos = true;
  image.keep_overlays = true;
  for (std::size_t i = 0; i < ctx.tests().size(); ++i) {
    const LabTest& test = ctx.tests()[i];
    const fs::path rel = fs::path("photos") / test.id;
    fs::create_directories(dir / rel);
    PhotoPair& p = pairs.emplace_back();
    p.id = test.id;
    cameras.push_back(0);
    if (!test.photos.empty()) p.lab = lab_view(test, ctx.data->file, dir, rel, cameras.back());
    p.note = state.model.no_pile(i);
    if (!p.note.empty()) {  // the twin's pours jammed: nothing to photograph
      for (const char* f : {"twin.png", "twin.measured.png"}) fs::remove(dir / rel / f);
      continue;
    }
    const Curve& c = surf.curve.at(i);
    const std::size_t j = nearest(c.mu, state.fit.mu);
    p.mu_r = c.mu[j];
    p.seed = surf.raw.at(i).at(j).at(0).seed;  // the pour that made the first seed's pile
    for (const EffectSetting& e : surf.effects) p.effects.emplace_back(e.effect->name, e.value);
    requests.push_back(make_request(test, s.mu_key, p.mu_r, p.seed, surf.effects, image));
    asked.push_back(i);
    // The lab photo's camera picks the twin's view only when the twin photographs through the
    // lab's cameras (else its own framing's first view).
    if (requests.back().image.lab_cameras.empty()) cameras.back() = 0;
  }
  if (requests.empty()) return pairs;
  ctx.say("photographing " + std::to_string(requests.size()) + " twin pile(s) for the page");
  std::vector<std::string> notes(requests.size());
  const std::vector<std::optional<SimOutcome>> out = photograph_for_page(store, requests, notes);
  for (std::size_t k = 0; k < requests.size(); ++k) {
    PhotoPair& p = pairs[asked[k]];
    p.note = notes[k];
    const fs::path rel = fs::path("photos") / p.id;
    if (out[k]) p.twin = twin_view(*out[k], cameras[asked[k]], dir, rel, p.note);
    if (!p.twin)  // not a stale one of an earlier run beside the note
      for (const char* f : {"twin.png", "twin.measured.png"}) fs::remove(dir / rel / f);
  }
  return pairs;
}

}  // namespace reposetwin::experiments::loop_detail
