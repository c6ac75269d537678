#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/reposetwin/commands.hpp"
#include "apps/reposetwin/validators.hpp"
#include "camera/camera.hpp"
#include "experiments/io/files.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "experiments/photos/pile_images.hpp"
#include "experiments/pile/run_state.hpp"
#include "experiments/report/run_stages.hpp"

namespace reposetwin::cli {

void add_render_command(CLI::App& app) {
  struct Args {
    std::string run_dir;
    experiments::ImageSettings images;
    std::vector<std::string> frames;
    std::vector<std::string> cameras;
    bool force = false;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "render", "Photograph a finished run's pile (side views and top view) and measure the images");
  cmd->add_option("run_dir", args->run_dir, "Run folder written by `reposetwin run`")->required();
  // Bounds that keep a typo from rendering for hours or allocating gigabytes: a few views
  // measure the angle (the lab takes four), and a frame above 16k pixels a side is no camera's.
  cmd->add_option("--views", args->images.side_views, "Side views over 180 degrees")
      ->capture_default_str()
      ->check(whole_number_in(1, 64));
  cmd->add_option("--width", args->images.width_px, "Image width [px]")
      ->capture_default_str()
      ->check(whole_number_in(64, 16384));
  cmd->add_option("--height", args->images.height_px, "Image height [px]")
      ->capture_default_str()
      ->check(whole_number_in(64, 16384));
  cmd->add_option("--camera-height", args->images.camera_height_m,
                  "Side camera height above the plate [m]")
      ->capture_default_str()
      ->check(number_in(0.0, 10.0));
  cmd->add_flag("!--no-top", args->images.top_view, "Skip the top view");
  cmd->add_option("--frame", args->frames,
                  "Also photograph these snapshots of the series (e.g. frames/frame_00004.vtp)");
  cmd->add_option("--camera", args->cameras,
                  "Photograph with the lab's side camera of this sidecar JSON (repeat for each "
                  "view): its pose, lens and resolution, as many views at its azimuths");
  cmd->add_flag("--force", args->force, "Replace the run's earlier photographs");
  cmd->callback([args]() {
    // Photographs are results: an earlier set (run's own, or an earlier render) stays unless
    // asked, checked before anything is rendered.
    namespace fs = std::filesystem;
    const std::string& dir = args->run_dir;
    // images -> elsewhere would aim the photographs and --force at another folder.
    experiments::refuse_escaping_links(dir);
    std::vector<fs::path> outputs = {fs::path(dir) / "images" / "measurement.json"};
    for (const std::string& f : args->frames)
      outputs.push_back(fs::path(dir) / "images" / fs::path(f).stem() / "measurement.json");
    for (const fs::path& p : outputs)
      if (fs::exists(p) && !args->force)
        throw experiments::InputError(p.string() +
                                      ": photographs are already there; pass --force to replace "
                                      "them");
    experiments::refuse_repeated_contents(args->cameras, "render --camera");
    for (const std::string& path : args->cameras) {
      try {
        args->images.lab_cameras.push_back(camera::read_sidecar(path));
      } catch (const std::exception& e) {
        throw experiments::InputError(std::string("--camera: ") + e.what());
      }
    }
    if (!fs::is_regular_file(fs::path(dir) / "result.json"))
      throw experiments::InputError(dir + ": not a finished run (result.json is missing)");
    const experiments::RunFolderLock lock(dir);
    // The stage record says what the folder holds (pile/run_state.hpp): a run not recorded as
    // simulated is finished by --resume first.
    if (!experiments::read_run_state(dir))
      throw experiments::InputError(dir +
                                    ": the run is not recorded as simulated (no run_state.json); "
                                    "finish it with `reposetwin run --resume --out " +
                                    dir + "`");
    const experiments::PileRun run = experiments::pile_run_from_json(
        nlohmann::json::parse(experiments::read_file(dir + "/result.json")));
    if (run.pile.status == sim::PileStatus::kNoPile)
      throw experiments::InputError(dir + ": the run formed no pile (" + run.stop.detail +
                                    "); nothing to photograph");
    const experiments::SceneConfig scene =
        experiments::load_scene((fs::path(dir) / "scene.resolved.toml").string());
    // Each view is measured on its own: one view vision cannot read is reported, and the others
    // still give the angle.
    args->images.views_must_measure = false;
    for (const std::string& f : args->frames)
      experiments::render_and_measure_run(dir, args->images, f);
    // New photographs invalidate everything made from the old ones: the record goes back to
    // simulated (removing the old views, measurement.json and the page), then the stages are
    // made again from these, the headline in result.json and summary.html included.
    experiments::rewind_run_state(dir, experiments::RunStage::kSimulated, true);
    experiments::RunStagesRequest req;
    req.run_dir = dir;
    req.images = args->images;
    req.started = std::chrono::steady_clock::now();
    const experiments::RunStagesOutcome done = experiments::finish_run_stages(run, scene, req);
    const fs::path measurement = fs::path(dir) / "images" / "measurement.json";
    const nlohmann::json m =
        fs::exists(measurement)
            ? nlohmann::json::parse(experiments::read_file(measurement.string()))
            : nlohmann::json{{"side_views", nlohmann::json::array()}};
    for (const nlohmann::json& v : m["side_views"])
      if (v.contains("error"))
        std::cerr << "warning: " << dir << "/images/" << v["image"].get<std::string>()
                  << " not measured: " << v["error"].get<std::string>() << "\n";
    if (!done.state.complete())
      throw std::runtime_error(dir + "/images: no side view could be measured (" +
                               done.inputs.images_error + "); the run is incomplete");
    std::cout << nlohmann::json{{"theta_deg", m["theta_deg"]},
                                {"theta_sd_deg", m["theta_sd_deg"]},
                                {"height_m", m["height_m"]},
                                {"diameter_m", m["diameter_m"]},
                                {"images", dir + "/images"}}
                     .dump(2)
              << "\n";
  });
}

}  // namespace reposetwin::cli
