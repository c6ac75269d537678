#include "experiments/loop/loop.hpp"

#include "experiments/campaign/case_runner.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <set>
#include <stdexcept>

#include "experiments/io/format.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace loop_detail {
namespace {

// OUT/loop.json (atomic) and OUT/index.html, from the records' one to_json. loop.json first: the
// page reads its record back, and a page that fails must not lose the loop's result; the error
// then says so and how to make the page from the file.
json write(const LoopContext& ctx, const LoopRecord& rec) {
  const json loop = to_json(rec);
  fs::create_directories(ctx.out);
  const std::string path = (fs::path(ctx.out) / "loop.json").string();
  write_made_file(path, loop.dump(2) + "\n");
  if (!ctx.s().html) return loop;
  try {
    ctx.s().page(loop, ctx.out);
  } catch (const std::exception& e) {
    throw std::runtime_error(path + " is written, but its page is not: " + e.what() +
                             " (reposetwin report " + ctx.out + " makes it from the file)");
  }
  return loop;
}

// The table of contents (loop.hpp's design note): each stage returns the records loop.json is
// made of; the store is passed only to the stages that pour piles.
json run_stages(const LabData& data, const std::string& out, const LoopSettings& s) {
  PileStore store{SimCache(s.cache_dir.empty() ? (fs::path(out) / "cache").string() : s.cache_dir,
                           {s.workers, s.progress}),
                  {}};
  const LoopContext setup = check_settings(data, out, s);
  const auto t_start = std::chrono::steady_clock::now();
  LoopRecord rec;
  rec.tests = data.tests;
  rec.rule = s.rule;
  rec.design = setup.design;

  Baseline base = baseline(setup, store);
  rec.grid = settle_grid(base, store);
  rec.baseline = base.record;
  const LoopContext& ctx = base.ctx;  // on the settled grid, with its seed noise

  LoopState state;
  state.model.terms = {{1.0, base.surface}};
  state.fit = rec.baseline.fit;
  rec.not_traced = not_traced(ctx, rec.grid);
  if (rec.not_traced) {
    ctx.say("nothing traced: " + *rec.not_traced);
  } else {
    const std::size_t node = ctx.nearest_grid_point(rec.baseline.fit.mu);
    Fingerprints fps = fingerprint_candidates(ctx, store, *base.surface, node);
    rec.fingerprints = std::move(fps.records);
    rec.unavailable = std::move(fps.unavailable);
    for (int it = 0; it < s.max_effects + 1; ++it)
      if (!iterate(ctx, store, it, state, rec.fingerprints, node, rec.iterations)) break;
  }

  rec.final_model = final_record(ctx, state);
  rec.photo_pairs = photo_pairs(ctx, store, state);
  rec.provenance = provenance(ctx, store, *base.surface);
  rec.simulations = {
      store.cache.simulations_started(), store.cache.photos_started(),
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count()};
  rec.summary = summarise(rec);
  return write(ctx, rec);
}

}  // namespace
}  // namespace loop_detail

LabData lab_angles(const LabData& data, AngleMeasure measure) {
  if (measure == AngleMeasure::kSlice)
    throw InputError(data.file +
                     ": the loop cannot compare the 'slice' angle (a protractor on "
                     "particle slices has no counterpart in a lab's photos or sheet); use image, "
                     "image_flank or particles");
  LabData out = data;
  for (LabTest& t : out.tests) {
    if (t.photos.empty()) continue;  // a typed angle (or H and D) is used as given
    if (measure == AngleMeasure::kImageFlank) {
      const json& f =
          t.photo_measurement.contains("flank_deg") ? t.photo_measurement["flank_deg"] : json();
      if (!f.is_object() || !f.contains("mean") || !f["mean"].is_number())
        throw InputError(data.file + " line " + std::to_string(t.line) + " (test " + t.id +
                         "), column photo: the photos' measurement has no flank angle");
      t.angle_deg = f["mean"].get<double>();
    }
    t.photo_measurement["compared_angle"] = {{"measure", angle_measure_name(measure)},
                                             {"angle_deg", t.angle_deg}};
  }
  return out;
}

std::string lab_angle_source(AngleMeasure measure) {
  if (measure == AngleMeasure::kImageFlank)
    return "tests with photos: the flank angle vision measured on them; tests with a typed "
           "angle (or H and D): that value, taken as the flank angle (the lab pile assumed a "
           "full cone)";
  return "tests with photos: atan(2H/D) vision measured on them; others: the typed angle (or "
         "atan(2H/D) of the typed H and D)";
}

double twin_angle(const SimOutcome& o, AngleMeasure measure) {
  if (measure == AngleMeasure::kSlice)
    throw std::runtime_error("the loop compares image, image_flank or particles angles, not slice");
  if (!o.pile) return 0.0;  // a pour without a measured pile has no angle to compare
  if (measure == AngleMeasure::kImageFlank && !std::isfinite(o.flank_deg))
    throw std::runtime_error(o.image_dir +
                             ": this photograph's measurement has no flank angle (made by an "
                             "older version); use a fresh --cache");
  // The campaign's selector (case_runner.hpp), on the loop's record in metres.
  PileMeasure pile;
  pile.theta_hd_deg = o.positions_angle_deg;
  const PhotoMeasure photo{o.angle_deg,          0.0,         1e-3 * o.height_mm,
                           1e-3 * o.diameter_mm, o.flank_deg, 1e-3 * o.crest_mm};
  return select_angle_deg(pile, photo, measure, o.image_dir);
}

std::string grid_bound_name(GridBound g) {
  switch (g) {
    case GridBound::kExtend:
      return "extend";
    case GridBound::kRefuse:
      return "refuse";
    case GridBound::kTrace:
      return "trace";
  }
  return "extend";
}

GridBound parse_grid_bound(const std::string& text, const std::string& option) {
  for (GridBound g : {GridBound::kExtend, GridBound::kRefuse, GridBound::kTrace})
    if (grid_bound_name(g) == text) return g;
  throw InputError(option + ": \"" + text + "\" is not one of extend, refuse, trace");
}

json run_loop(const LabData& data, const std::string& out_dir, const LoopSettings& settings) {
  const LabData compared = lab_angles(data, settings.angle);
  return loop_detail::run_stages(compared, out_dir, settings);
}

BatchPlan plan_loop_baseline(const LabData& data, const LoopSettings& s) {
  std::vector<BatchPlan::Part> parts;
  const int runs = static_cast<int>(s.mu_grid.size() * s.seeds.size());
  for (const LabTest& t : data.tests) {
    std::vector<std::string> sets;
    for (const auto& [key, value] : t.overrides) sets.push_back(key + "=" + value);
    parts.push_back({"baseline piles of test " + t.id + " (" + std::to_string(s.mu_grid.size()) +
                         " mu_r x " + std::to_string(s.seeds.size()) + " seeds)",
                     plan_run(load_scene(t.scene_path, sets), 1), runs});
  }
  return plan_batch(std::move(parts), s.workers);
}

}  // namespace reposetwin::experiments
