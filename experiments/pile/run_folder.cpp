#include "experiments/pile/run_folder.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <regex>
#include <system_error>

#include "experiments/io/files.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/pile/run_state.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;

namespace {

// A temporary of an atomic write (write_file_atomic's "NAME.tmp.PID", the checkpoint's
// "NAME.tmp") left by a killed run.
const std::regex kTemporary(R"((.+)\.tmp(\.[0-9]+)?)");
// The run's own files, by folder. Photographs: side views at their azimuths (a second view at
// one azimuth gets "_2"), the top view, each with its sidecar and its measured overlay.
const std::regex kTopFile(R"(result\.json|final\.vtp|checkpoint\.bin|controller\.json|series\.pvd|)"
                          R"(scene\.resolved\.toml|summary\.html|\.run\.lock|run_state\.json|)"
                          R"(\.reposetwin-made\.json)");
// The files only a pile run makes: a folder with none of them is not a run's, even if it holds a
// summary.html or an images/ folder of a person's own.
const std::regex kRunMarker(
    R"(result\.json|final\.vtp|checkpoint\.bin|controller\.json|series\.pvd|scene\.resolved\.toml|)"
    R"(run_state\.json)");
const std::regex kFrameFile(
    R"((frame|container|contacts)_[0-9]{5}\.vtp|plate\.vtp|filled\.vtp)");
const std::regex kImageFile(
    R"(measurement\.json|\.reposetwin-made\.json|)"
    R"((side_az[0-9]{3}(_[0-9]+)?|top)(\.measured)?\.(png|json))");
// `reposetwin report RUN_DIR` writes its page, data, plots and copied renders into report/.
const std::regex kReportFile(R"([A-Za-z0-9_.-]+\.(html|json|png|dat|gp))");
// `reposetwin render --frame frames/frame_00004.vtp` photographs into images/frame_00004/.
const std::regex kImageFolder(R"(frame_[0-9]{5})");

std::string without_temporary(const std::string& name) {
  std::smatch m;
  return std::regex_match(name, m, kTemporary) ? m[1].str() : name;
}

bool is_dir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

std::string list(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// Where an interrupted run stopped, as its record says.
std::string interrupted_at(const fs::path& dir) {
  try {
    if (const std::optional<RunState> s = read_run_state(dir.string()))
      return "stage " + std::string(run_stage_name(s->stage)) + " recorded; missing: " +
             s->missing() + (s->note.empty() ? "" : "; " + s->note);
  } catch (const RunStateError& e) {
    return e.what();
  }
  std::error_code ec;
  if (fs::exists(dir / "result.json", ec))
    return "result.json without a complete stage record (run_state.json)";
  return "checkpoint.bin, no result.json";
}

}  // namespace

bool is_run_file(const fs::path& relative) {
  std::vector<std::string> parts;
  for (const fs::path& part : relative) parts.push_back(part.string());
  if (parts.empty()) return false;
  const std::string name = without_temporary(parts.back());
  if (parts.size() == 1) return std::regex_match(name, kTopFile);
  if (parts.size() == 2 && parts[0] == "frames") return std::regex_match(name, kFrameFile);
  if (parts.size() == 2 && parts[0] == "report") return std::regex_match(name, kReportFile);
  if (parts[0] != "images") return false;
  if (parts.size() == 2) return std::regex_match(name, kImageFile);
  return parts.size() == 3 && std::regex_match(parts[1], kImageFolder) &&
         std::regex_match(name, kImageFile);
}

RunFolderState run_folder_state(const fs::path& dir, std::vector<std::string>* foreign) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) return RunFolderState::kAbsent;
  bool any = false, marked = false;
  std::vector<std::string> others;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::end(it);
       it.increment(ec)) {
    if (it->is_directory(ec)) continue;
    const fs::path rel = fs::relative(it->path(), dir, ec);
    if (rel == ".run.lock") continue;
    any = true;
    if (!is_run_file(rel)) others.push_back(rel.string());
    if (rel.has_filename() && rel == rel.filename() &&
        std::regex_match(without_temporary(rel.string()), kRunMarker))
      marked = true;
  }
  if (any && !marked && others.empty()) {  // a run's names, but no run's own file among them
    for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::end(it);
         it.increment(ec))
      if (!it->is_directory(ec) && it->path().filename() != ".run.lock")
        others.push_back(fs::relative(it->path(), dir, ec).string());
  }
  if (!others.empty()) {
    std::sort(others.begin(), others.end());
    if (foreign)
      foreign->assign(others.begin(),
                      others.begin() + std::min<std::ptrdiff_t>(3, std::ssize(others)));
    return RunFolderState::kForeign;
  }
  if (!any) return RunFolderState::kEmpty;
  // The stage record decides (pile/run_state.hpp): a result.json without a complete record is
  // a run stopped between stages, and so is a record that cannot be trusted.
  try {
    if (const std::optional<RunState> s = read_run_state(dir.string()); s && s->complete())
      return RunFolderState::kFinished;
  } catch (const RunStateError&) {
    return RunFolderState::kInterrupted;
  }
  if (fs::exists(dir / "result.json", ec) || fs::exists(dir / kRunStateFile, ec) ||
      fs::exists(dir / "checkpoint.bin", ec) || fs::exists(dir / "controller.json", ec))
    return RunFolderState::kInterrupted;
  return RunFolderState::kStarted;
}

void check_output_folder(const std::string& out, const std::string& option) {
  if (out.empty())
    throw InputError(option + " is empty: name a folder (for example " + option + " runs/my_pile)",
                     option);
  const fs::path dir(out);
  std::error_code ec;
  const fs::file_status st = fs::status(dir, ec);
  if (fs::exists(st) && !fs::is_directory(st))
    throw InputError(out + ": " + option + " names a file, not a folder; give a folder", option);
  // Where the folder would be created: the nearest part of the path that exists must be a
  // folder this process can write into.
  fs::path existing = fs::absolute(dir, ec).lexically_normal();
  while (!existing.empty() && !fs::exists(existing, ec) && existing != existing.parent_path())
    existing = existing.parent_path();
  if (!is_dir(existing))
    throw InputError(out + ": " + option + ": cannot make the folder: " + existing.string() +
                         " is a file, not a folder",
                     option);
  if (::access(existing.c_str(), W_OK | X_OK) != 0) {
    const std::string why = std::error_code(errno, std::generic_category()).message();
    const bool itself = existing == fs::absolute(dir, ec).lexically_normal();
    throw InputError(
        out + ": " + option + ": cannot " +
            (itself ? std::string("write into the folder: ") : std::string("make the folder: ")) +
            existing.string() + " is not writable (" + why + ")",
        option);
  }
}

void check_run_folder(const std::string& out, bool resume, bool force) {
  check_output_folder(out);
  refuse_escaping_links(out);
  const fs::path dir(out);
  std::vector<std::string> foreign;
  switch (run_folder_state(dir, &foreign)) {
    case RunFolderState::kAbsent:
    case RunFolderState::kEmpty:
    case RunFolderState::kStarted:
      if (resume)
        throw InputError(out + ": no checkpoint to resume from (checkpoint.bin, controller.json)",
                         "--resume");
      return;
    case RunFolderState::kFinished:
      if (resume && !force)
        throw InputError(out + "/result.json: the run is already finished; nothing to resume",
                         "--resume");
      if (!force)
        throw InputError(out +
                             "/result.json: a finished result is already there; pass --force "
                             "to overwrite it",
                         "--force");
      return;
    case RunFolderState::kInterrupted:
      if (!resume && !force)
        throw InputError(out + ": an interrupted run is there (" + interrupted_at(dir) +
                             "); continue it with --resume, or pass --force to start again",
                         "--resume");
      return;
    case RunFolderState::kForeign:
      if (!force)
        throw InputError(out + ": is not a run folder (it holds " + list(foreign) +
                             "); choose another --out, or pass --force (a run then replaces "
                             "only its own files)",
                         "--out");
      return;
  }
}

void remove_run_files(const fs::path& dir) {
  std::error_code ec;
  std::vector<fs::path> files, folders;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::end(it);
       it.increment(ec)) {
    const fs::path rel = fs::relative(it->path(), dir, ec);
    if (it->is_directory(ec))
      folders.push_back(it->path());
    else if (is_run_file(rel) && rel != ".run.lock")
      files.push_back(it->path());
  }
  for (const fs::path& f : files) fs::remove(f, ec);
  // Deepest first; fs::remove leaves a folder that still holds a user's file.
  std::sort(folders.begin(), folders.end(),
            [](const fs::path& a, const fs::path& b) { return a.string() > b.string(); });
  for (const fs::path& f : folders) {
    const fs::path rel = fs::relative(f, dir, ec);
    const std::string top = rel.begin()->string();
    if ((top == "frames" || top == "images" || top == "report") && fs::is_empty(f, ec))
      fs::remove(f, ec);
  }
}

}  // namespace reposetwin::experiments
