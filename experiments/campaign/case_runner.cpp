#include "experiments/campaign/case_runner.hpp"

#include <filesystem>
#include <stdexcept>

#include "experiments/pile/pile_run.hpp"
#include "experiments/io/scene.hpp"

namespace reposetwin::experiments {
using nlohmann::json;

CaseFn pile_case_fn(const CaseRunSettings& settings) {
  return [settings](const CaseSpec& spec, const std::string& case_dir) -> json {
    toml::table doc = build_case_scene(spec);
    if (toml::table* s = doc["scene"].as_table())
      s->insert_or_assign("seed", static_cast<std::int64_t>(spec.seed));
    const SceneConfig scene = parse_scene_table(doc, spec.scene_path);
    RunOptions opt;
    opt.out_dir = (std::filesystem::path(case_dir) / "run").string();
    opt.progress = false;
    opt.threads = settings.threads;
    opt.extra_provenance = {{"campaign_case", spec.id()}};
    const json run = run_pile_test_or_continue(scene, opt);
    json out = {{"stop", run.at("stop")},
                {"pile", run.at("pile")},
                {"particles", run.at("particles")},
                {"performance", run.at("performance")},
                {"provenance", run.at("provenance")},
                {"psd_fines_fraction", run.at("psd").at("fines_fraction_not_simulated")},
                {"run_dir", "run"}};
    if (settings.images && run.at("pile").at("status") == "ok") {
      const json m = render_and_measure_run(opt.out_dir, settings.image);
      out["image"] = {{"theta_deg", m.at("theta_deg")},
                      {"theta_sd_deg", m.at("theta_sd_deg")},
                      {"height_m", m.at("height_m")},
                      {"diameter_m", m.at("diameter_m")},
                      {"flank_deg", m.at("flank_deg")},
                      {"images", "run/images"}};
    }
    return out;
  };
}

bool case_made_no_pile(const json& r) {
  const json& res = r.contains("result") ? r.at("result") : r;
  return res.contains("pile") && res["pile"].value("status", std::string()) == "no pile";
}

double case_angle_deg(const json& r, AngleMeasure measure) {
  const json& res = r.contains("result") ? r.at("result") : r;
  if (res.contains("stop")) {
    const std::string reason = res.at("stop").value("reason", std::string());
    if (reason.rfind("physics", 0) == 0)
      throw std::runtime_error("the run stopped on a physics failure (" + reason + ": " +
                               res.at("stop").value("detail", std::string()) +
                               "), so it has no angle; " + res.value("run_dir", std::string()));
  }
  if (case_made_no_pile(res)) return 0.0;
  switch (measure) {
    case AngleMeasure::kImage:
      if (res.contains("image")) return res.at("image").at("theta_deg");
      return res.at("pile").at("theta_hd_deg");
    case AngleMeasure::kImageFlank:
      if (!res.contains("image"))
        throw std::runtime_error("the image flank angle needs the run's photographs, and " +
                                 res.value("run_dir", std::string("this run")) +
                                 " has none (run without --no-images)");
      return res.at("image").at("flank_deg");
    case AngleMeasure::kParticles:
      return res.at("pile").at("theta_hd_deg");
    case AngleMeasure::kSlice:
      return res.at("pile").at("slice_angle_mean_deg");
  }
  throw std::logic_error("case_angle_deg: unknown angle measure");
}

}  // namespace reposetwin::experiments
