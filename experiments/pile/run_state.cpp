#include "experiments/pile/run_state.hpp"

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <stdexcept>

#include "experiments/io/files.hpp"
#include "experiments/io/hash.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kFormat = "reposetwin-run-state";
constexpr int kVersion = 1;

std::size_t index(RunStage s) { return static_cast<std::size_t>(s); }

// The record's fields without the checksum, the text the checksum is taken over.
json fields(const RunState& s) {
  return {{"format", kFormat},
          {"version", kVersion},
          {"stage", run_stage_name(s.stage)},
          {"photographs", s.photographs},
          {"note", s.note}};
}

std::string checksum(const json& f) { return fnv1a_hex(f.dump()); }

fs::path state_path(const std::string& dir) { return fs::path(dir) / kRunStateFile; }

RunState read_existing(const std::string& dir, const char* what) {
  const std::optional<RunState> s = read_run_state(dir);
  if (!s)
    throw std::logic_error(std::string(what) + ": " + dir +
                           " has no run_state.json (the run was not recorded as simulated)");
  return *s;
}

void write_state(const std::string& dir, const RunState& s) {
  write_file_atomic(state_path(dir).string(), run_state_text(s));
}

// The files a stage owns in the run folder, relative to it: removed when the record is lowered
// below that stage.
const std::regex kPhotoFile(R"((side_az[0-9]{3}(_[0-9]+)?|top)(\.measured)?\.(png|json))");

// The tests' kill at a stage boundary: after the record is on disk, as a crash there would be.
void kill_if_asked(RunStage stage) {
  if (const char* kill = std::getenv("REPOSETWIN_TEST_KILL_AFTER_STAGE");
      kill && std::string_view(kill) == run_stage_name(stage))
    std::raise(SIGKILL);
}

}  // namespace

const char* run_stage_name(RunStage s) {
  if (s == RunStage::kCount) throw std::logic_error("run_stage_name: kCount is not a stage");
  return kRunStageNames[index(s)];
}

std::optional<RunStage> run_stage_from(std::string_view word) {
  for (std::size_t i = 0; i < kRunStageNames.size(); ++i)
    if (word == kRunStageNames[i]) return static_cast<RunStage>(i);
  return std::nullopt;
}

bool run_stage_follows(RunStage from, RunStage to, bool photographs) {
  if (from == RunStage::kSimulated && !photographs) return to == RunStage::kSummarised;
  return index(to) == index(from) + 1 && to != RunStage::kCount;
}

std::optional<RunStage> RunState::next() const {
  if (complete()) return std::nullopt;
  if (stage == RunStage::kSimulated && !photographs) return RunStage::kSummarised;
  return static_cast<RunStage>(index(stage) + 1);
}

std::string RunState::missing() const {
  std::string out;
  RunState s = *this;
  while (const std::optional<RunStage> n = s.next()) {
    out += (out.empty() ? "" : ", ") + std::string(run_stage_name(*n));
    s.stage = *n;
  }
  return out;
}

std::string run_state_text(const RunState& s) {
  json j = fields(s);
  j["checksum_fnv1a"] = checksum(fields(s));
  return j.dump(2) + "\n";
}

RunState run_state_from_text(const std::string& text, const std::string& path) {
  const auto bad = [&path](const std::string& why) {
    return RunStateError(path + ": " + why +
                         "; the run's stage cannot be trusted: run it again with --force");
  };
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception&) {
    throw bad("is not valid JSON (damaged or cut short)");
  }
  if (!j.is_object()) throw bad("is not a run-state record (not a JSON object)");
  static const std::set<std::string> kKeys = {"format",      "version", "stage",
                                              "photographs", "note",    "checksum_fnv1a"};
  for (const auto& [key, value] : j.items())
    if (!kKeys.count(key)) throw bad("has an unknown field \"" + key + "\"");
  for (const std::string& key : kKeys)
    if (!j.contains(key)) throw bad("lacks the field \"" + key + "\"");
  if (j["format"] != kFormat)
    throw bad("format is " + j["format"].dump() + ", not \"" + kFormat + "\"");
  if (j["version"] != kVersion)
    throw bad("version is " + j["version"].dump() + "; this program reads version " +
              std::to_string(kVersion));
  if (!j["stage"].is_string()) throw bad("stage is " + j["stage"].dump() + ", not a word");
  const std::optional<RunStage> stage = run_stage_from(j["stage"].get<std::string>());
  if (!stage) throw bad("stage " + j["stage"].dump() + " is not a stage of a run");
  if (!j["photographs"].is_boolean()) throw bad("photographs is " + j["photographs"].dump());
  if (!j["note"].is_string()) throw bad("note is " + j["note"].dump());
  RunState s;
  s.stage = *stage;
  s.photographs = j["photographs"].get<bool>();
  s.note = j["note"].get<std::string>();
  if (j["checksum_fnv1a"] != checksum(fields(s)))
    throw bad("its checksum does not match its fields (edited or damaged)");
  return s;
}

std::optional<RunState> read_run_state(const std::string& dir) {
  const fs::path p = state_path(dir);
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(p, ec))) return std::nullopt;
  std::string text;
  try {
    text = read_file(p.string(), 1u << 16);
  } catch (const InputError& e) {
    throw RunStateError(e.what());
  }
  return run_state_from_text(text, p.string());
}

void record_simulated(const std::string& dir, bool photographs) {
  RunState s;
  s.photographs = photographs;
  write_state(dir, s);
  kill_if_asked(RunStage::kSimulated);
}

void record_stage(const std::string& dir, RunStage stage) {
  RunState s = read_existing(dir, "record_stage");
  if (!run_stage_follows(s.stage, stage, s.photographs))
    throw std::logic_error(std::string("record_stage: ") + dir + " is at " +
                           run_stage_name(s.stage) + "; " + run_stage_name(stage) +
                           " cannot follow it");
  s.stage = stage;
  s.note.clear();
  write_state(dir, s);
  kill_if_asked(stage);
}

void record_note(const std::string& dir, const std::string& note) {
  RunState s = read_existing(dir, "record_note");
  s.note = note;
  write_state(dir, s);
}

void rewind_run_state(const std::string& dir, RunStage stage, bool photographs) {
  RunState s = read_existing(dir, "rewind_run_state");
  if (index(stage) > index(s.stage))
    throw std::logic_error(std::string("rewind_run_state: ") + dir + " is at " +
                           run_stage_name(s.stage) + ", below " + run_stage_name(stage));
  // The record first: a kill during the removals leaves a folder that says it is incomplete.
  s.stage = stage;
  s.photographs = photographs;
  s.note.clear();
  write_state(dir, s);
  std::error_code ec;
  const fs::path base(dir);
  if (index(stage) < index(RunStage::kReported)) fs::remove(base / "summary.html", ec);
  if (index(stage) < index(RunStage::kMeasured))
    fs::remove(base / "images" / "measurement.json", ec);
  if (index(stage) < index(RunStage::kPhotographed) && fs::is_directory(base / "images", ec))
    for (const fs::directory_entry& e : fs::directory_iterator(base / "images", ec))
      if (e.is_regular_file(ec) && std::regex_match(e.path().filename().string(), kPhotoFile))
        fs::remove(e.path(), ec);
}

RunFolderLock::RunFolderLock(const std::string& dir)
    : lock_(dir, ".run.lock", "another reposetwin command (run, render or report)") {}

}  // namespace reposetwin::experiments
