// A user's own calibration, end to end, as a lab runs it: photographs of a pile (made by the twin
// itself, with their camera sidecars, at a known mu_r), a CSV test sheet naming them, a CSV sieve
// sheet and a base scene, given to `reposetwin calibrate --tests --sieve --scene`. The plan comes
// first, the two ends of the mu_r range are run first, the target is the photos' angle as the
// twin reads its own, and a mu_r comes out; a target the range cannot reach is said after those
// two points, in numbers, with what to try, and a non-zero exit.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/apps/cli_support.hpp"

namespace {
namespace fs = std::filesystem;
using reposetwin::test_support::fresh_dir;
using reposetwin::test_support::quoted;
using reposetwin::test_support::read_text;
using reposetwin::test_support::run_cli;
using reposetwin::test_support::write_text;

const fs::path kScene = fs::path(REPOSETWIN_SOURCE_DIR) / "data" / "loop" / "tiny_scene.toml";
constexpr const char* kSieve =
    "# the lab's sieve sheet\nsieve_mm,passing_percent\n3.0,0\n3.5,45\n4.0,100\n";
constexpr double kLabMuR = 0.25;  // the mu_r the "lab" photos are made at

std::string side_photos(const fs::path& images) {
  std::string list;
  for (const auto& e : fs::directory_iterator(images)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("side", 0) == 0 && e.path().extension() == ".png" &&
        name.find(".measured") == std::string::npos) {
      EXPECT_TRUE(fs::exists(fs::path(e.path()).replace_extension(".json")))
          << "no camera sidecar beside " << name;
      list += (list.empty() ? "" : ";") + fs::relative(e.path(), images.parent_path().parent_path())
                                              .string();
    }
  }
  return list;
}

TEST(UserCalibration, FromTheLabsSheetsToMuR) {
  const auto t0 = std::chrono::steady_clock::now();
  const fs::path d = fresh_dir("user_calibration");
  write_text(d / "sieve.csv", kSieve);
  // The lab's pile, photographed by the twin (4 side views, each with its sidecar).
  const auto lab = run_cli("run " + quoted(kScene) + " --out " + quoted(d / "lab") +
                           " --quiet --threads 1 --set sample.psd_file=" + quoted(d / "sieve.csv") +
                           " --set contacts.rock-rock.rolling_friction=" + std::to_string(kLabMuR));
  ASSERT_EQ(lab.code, 0) << lab.out;
  const std::string photos = side_photos(d / "lab" / "images");
  ASSERT_FALSE(photos.empty());
  write_text(d / "tests.csv", "# the lab's test sheet\nid,mass_g,W_mm,photo\nlab1,6,20," + photos +
                                  "\n");

  // Too large for the limits: refused before anything runs.
  const auto refused = run_cli("calibrate --tests " + quoted(d / "tests.csv") + " --sieve " +
                               quoted(d / "sieve.csv") + " --scene " + quoted(kScene) + " --out " +
                               quoted(d / "refused") + " --max-hours 0.000001");
  EXPECT_EQ(refused.code, 6) << refused.out;
  EXPECT_NE(refused.out.find("plan: "), std::string::npos) << refused.out;
  EXPECT_NE(refused.out.find("refused"), std::string::npos) << refused.out;
  EXPECT_FALSE(fs::exists(d / "refused" / "calibration.json"));

  const auto cal = run_cli("calibrate --tests " + quoted(d / "tests.csv") + " --sieve " +
                           quoted(d / "sieve.csv") + " --scene " + quoted(kScene) + " --out " +
                           quoted(d / "cal") + " --mu-r-range 0.05,0.5 --workers 2 --views 2");
  ASSERT_EQ(cal.code, 0) << cal.out;
  // The plan first: the order, the particle count and the estimated wall time.
  const auto plan_at = cal.out.find("plan: at most 8 pile runs, 2 at a time: estimated wall time");
  EXPECT_NE(plan_at, std::string::npos) << cal.out;
  EXPECT_NE(cal.out.find("the two ends of the range first"), std::string::npos) << cal.out;
  EXPECT_NE(cal.out.find(" particles (d 3-4 mm)"), std::string::npos) << cal.out;
  const nlohmann::json j = nlohmann::json::parse(read_text(d / "cal" / "calibration.json"));
  // The two ends first, both seeds each.
  const auto& pours = j.at("pours");
  ASSERT_GE(pours.size(), 4u);
  EXPECT_EQ(pours[0]["mu_r"].get<double>(), 0.05);
  EXPECT_EQ(pours[1]["mu_r"].get<double>(), 0.05);
  EXPECT_EQ(pours[2]["mu_r"].get<double>(), 0.5);
  EXPECT_EQ(pours[3]["mu_r"].get<double>(), 0.5);
  // The target is the lab photos' atan(2H/D), read through their sidecars exactly as the twin
  // read its own photographs of that pile (the lab run's headline).
  const nlohmann::json lab_result = nlohmann::json::parse(read_text(d / "lab" / "result.json"));
  EXPECT_NEAR(j["target"]["angle_deg"].get<double>(),
              lab_result["headline_angle_deg"].get<double>(), 1e-9);
  EXPECT_TRUE(j.contains("target_photos")) << "the target was not measured on the photos";
  // A mu_r inside its 95% interval, inside the range. (The tiny pile is a few grains high:
  // its angle moves by a few degrees over the whole range against a seed spread of one or two,
  // so the interval is wide; the order and the plumbing are what this test pins.)
  ASSERT_TRUE(j["mu_r"].is_number()) << j.dump(2);
  const double mu = j["mu_r"].get<double>();
  const double lo = j["mu_r_interval"][0].get<double>(), hi = j["mu_r_interval"][1].get<double>();
  EXPECT_LE(0.05, lo);
  EXPECT_LE(lo, mu);
  EXPECT_LE(mu, hi);
  EXPECT_LE(hi, 0.5);
  // Stopped because the seeds' spread alone is wider than the tolerance, said as such.
  if (j["status"] != "calibrated") EXPECT_EQ(j["status"], "seed_noise_limited") << j["message"];
  EXPECT_TRUE(fs::exists(d / "cal" / "campaign.toml"));
  EXPECT_NE(cal.out.find("mu_r "), std::string::npos) << cal.out;

  // The user's page leads with the user's answer: the calibration first, then the lab's own
  // target photo beside the twin's at one scale; no paper table on a user's calibration.
  const auto rep = run_cli("report " + quoted(d / "cal"));
  ASSERT_EQ(rep.code, 0) << rep.out;
  const std::string page = read_text(d / "cal" / "report" / "index.html");
  const auto at_cal = page.find("<h2>Calibration</h2>");
  const auto at_photo = page.find("<h2>Lab photo beside the simulated render</h2>");
  ASSERT_NE(at_cal, std::string::npos);
  ASSERT_NE(at_photo, std::string::npos) << "the lab's target photo is not on the page";
  EXPECT_LT(at_cal, at_photo);
  EXPECT_LT(at_photo, page.find("<h2>Cases</h2>"));
  EXPECT_EQ(page.find("Beside the paper's Table 3"), std::string::npos);
  EXPECT_NE(page.find("(the calibration"), std::string::npos);  // its caption
  const nlohmann::json summary =
      nlohmann::json::parse(read_text(d / "cal" / "report" / "summary.json"));
  EXPECT_TRUE(summary["lab_photo_common_mm_per_px"].is_number()) << "not at one scale";
  EXPECT_TRUE(fs::exists(d / "cal" / "report" / "lab_photo.measured.png"));
  EXPECT_TRUE(fs::exists(d / "cal" / "report" / "render_beside_lab.png"));

  // A target no mu_r in the range reaches: known after the two ends, said in numbers, with what
  // to try (the particle angle here: no photographs, so it costs the four pours alone).
  write_text(d / "steep.csv", "id,mass_g,W_mm,angle_deg\nsteep,6,20,60\n");
  const auto miss = run_cli("calibrate --tests " + quoted(d / "steep.csv") + " --sieve " +
                            quoted(d / "sieve.csv") + " --scene " + quoted(kScene) + " --out " +
                            quoted(d / "steep") + " --mu-r-range 0.05,0.5 --workers 2 --angle particles");
  EXPECT_EQ(miss.code, 5) << miss.out;
  EXPECT_NE(miss.out.find("cannot reach: the target 60 deg"), std::string::npos) << miss.out;
  EXPECT_NE(miss.out.find("kind = \"blocky\""), std::string::npos) << miss.out;
  EXPECT_NE(miss.out.find("contacts.rock-plate.friction"), std::string::npos) << miss.out;
  EXPECT_NE(miss.out.find("--angle image_flank"), std::string::npos) << miss.out;
  const nlohmann::json m = nlohmann::json::parse(read_text(d / "steep" / "calibration.json"));
  EXPECT_EQ(m["status"], "cannot_reach_high");
  EXPECT_EQ(m["pours"].size(), 4u) << "more than the two ends were run";
  const double secs =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("UserCalibration end to end: %.1f s\n", secs);
}

}  // namespace
