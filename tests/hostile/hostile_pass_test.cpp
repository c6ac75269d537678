// The hostile pass of docs/threat_model.md as one table: every subcommand of the built
// `reposetwin` given inputs a hostile or careless user would give it, each run in a folder of
// its own and classified from the outside, as a user would see it.
//
// Design note. A case is a setup (the files it makes in its folder), an argument vector (no
// shell: names may hold any byte), what it expects (a refusal, or for a valid input under a
// hostile name, success) and the words a clean refusal names (the file, the key or option, the
// value). The runner starts the command in its own process group with a 10 s limit and classifies:
//   clean     refused (non-zero exit) naming every word, nothing left behind
//   unclear   refused, but a word is missing, a library's raw text shows, or output was left
//   silent    exit 0 on a bad input
//   hung      killed at the time limit
//   crashed   ended by a signal, or an abort/uncaught exception message
//   refused valid  a valid input refused (expected success)
// and, independently of the exit, three faults seen on the disk:
//   data lost     a file the setup made changed or disappeared
//   path escape   anything written outside the case's folder (its siblings, HOME, TMPDIR)
//   injection     a file named INJECTED appeared (a name like `$(touch INJECTED)` was run)
// The cases are new: not those of tests/hostile/hostile_pass.sh, tests/apps/bad_input*_test.cpp
// or the fuzz corpora. The test fails when any fault count (unclear, silent, hung, crashed,
// refused valid, data lost, path escape, injection) is not 0, and prints the table; with
// REPOSETWIN_HOSTILE_CSV set it also writes every case's row there (tests/hostile/run_pass.sh).
// A lock file (.run.lock) left in a run folder is not output: every run folder keeps one.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;

constexpr int kTimeoutS = 10;

enum class Expect { kRefuse, kAccept };

enum class Outcome { kClean, kUnclear, kSilent, kHung, kCrashed, kRefusedValid, kAccepted, kCount };
constexpr std::array<const char*, static_cast<std::size_t>(Outcome::kCount)> kOutcomeNames = {
    "clean", "unclear", "silent", "hung", "crashed", "refused_valid", "accepted"};

using Setup = std::function<void(const fs::path& dir)>;

struct Case {
  std::string command;  // the subcommand, for the table by command
  std::string name;
  Expect expect = Expect::kRefuse;
  Setup setup;
  std::vector<std::string> argv;   // "{D}" stands for the case's folder
  std::vector<std::string> words;  // each must be in the message; "a~b": either
  bool may_write = false;          // a refusal may leave a page saying why (report, exit 11)
};

struct Result {
  Outcome outcome = Outcome::kClean;
  bool data_lost = false, escape = false, injection = false;
  int code = 0;
  double seconds = 0.0;
  std::string why, message;
};

// ---------------------------------------------------------------------------------------------
// Files.

std::string read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

void fifo(const fs::path& p) {
  fs::create_directories(p.parent_path());
  ASSERT_EQ(mkfifo(p.c_str(), 0644), 0) << p;
}

void link_to(const fs::path& p, const fs::path& target) {
  fs::create_directories(p.parent_path());
  fs::create_symlink(target, p);
}

void sparse(const fs::path& p, std::uintmax_t bytes) {
  write(p, "");
  fs::resize_file(p, bytes);
}

void copy_tree(const fs::path& from, const fs::path& to) {
  fs::create_directories(to.parent_path());
  fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::copy_symlinks);
}

// A file's state as the disk shows it: its type, size and, below 64 MB, a hash of its bytes.
std::string state_of(const fs::path& p) {
  std::error_code ec;
  const fs::file_status s = fs::symlink_status(p, ec);
  if (fs::is_symlink(s)) return "link:" + fs::read_symlink(p, ec).string();
  if (fs::is_directory(s)) return "dir";
  if (!fs::is_regular_file(s)) return "special";
  const std::uintmax_t size = fs::file_size(p, ec);
  if (size > (std::uintmax_t{64} << 20)) return "big:" + std::to_string(size);
  const std::string bytes = read_all(p);
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a
  for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  return "file:" + std::to_string(size) + ":" + std::to_string(h);
}

// Calls `f` on every path below `root`, never following a link (a link loop or a link to a
// FIFO is only a name here) and never entering `skip`.
void walk(const fs::path& root, const std::function<void(const fs::path&)>& f,
          const fs::path& skip = {}) {
  std::error_code ec;
  for (fs::directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path p = it->path();
    if (!skip.empty() && p == skip) continue;
    f(p);
    std::error_code sec;
    if (fs::is_directory(fs::symlink_status(p, sec))) walk(p, f, skip);
  }
}

// Every path below `root` with its state, `skip` and its contents left out.
std::map<std::string, std::string> snapshot(const fs::path& root, const fs::path& skip = {}) {
  std::map<std::string, std::string> m;
  walk(
      root, [&](const fs::path& p) { m[p.lexically_relative(root).string()] = state_of(p); }, skip);
  return m;
}

bool has_marker(const fs::path& root) {
  bool found = false;
  walk(root, [&](const fs::path& p) { found = found || p.filename() == "INJECTED"; });
  return found;
}

// ---------------------------------------------------------------------------------------------
// Running one case: posix_spawn, no shell, its own process group, a time limit.

struct Spawned {
  int code = -1;  // exit status, or -signal
  bool timed_out = false;
  double seconds = 0.0;
};

Spawned spawn(const std::vector<std::string>& argv, const fs::path& cwd, const fs::path& log,
              const std::vector<std::string>& env) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::vector<char*> envp;
  for (const std::string& e : env) envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  posix_spawn_file_actions_addchdir_np(&fa, cwd.c_str());
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attr, 0);
  pid_t pid = 0;
  const auto t0 = std::chrono::steady_clock::now();
  const int err = posix_spawn(&pid, argv[0].c_str(), &fa, &attr, args.data(), envp.data());
  posix_spawn_file_actions_destroy(&fa);
  posix_spawnattr_destroy(&attr);
  Spawned s;
  if (err != 0) return s;
  int status = 0;
  while (true) {
    const pid_t r = waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (t > kTimeoutS && !s.timed_out) {
      s.timed_out = true;
      kill(-pid, SIGKILL);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  kill(-pid, SIGKILL);  // anything the command left running in its group
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  s.code = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  return s;
}

bool contains(const std::string& text, const std::string& word) {
  std::size_t start = 0;
  while (true) {  // "a~b": either
    const std::size_t bar = word.find('~', start);
    const std::string alt = word.substr(start, bar == std::string::npos ? bar : bar - start);
    if (!alt.empty() && text.find(alt) != std::string::npos) return true;
    if (bar == std::string::npos) return false;
    start = bar + 1;
  }
}

// A library's own text where a message for a person was due.
const char* raw_library_text(const std::string& text) {
  for (const char* raw :
       {"std::", "basic_string", "filesystem error", "[json.exception", "what()", "stoi", "stod",
        "bad_alloc", "vector::", "map::at", "unordered_map", "Assertion", "terminate called",
        "cv::Exception", "OpenCV(", "vtkXML", "ERROR: In "})
    if (text.find(raw) != std::string::npos) return raw;
  return nullptr;
}

struct Pass {
  fs::path root;  // every case's folder lies in it, beside home/, tmp/ and outside/
  fs::path logs;  // outside root: the command's output
  std::string bin;
  std::vector<std::string> env;
};

Result run_case(const Pass& pass, const Case& c, int index) {
  const fs::path dir = pass.root / ("case_" + std::to_string(index));
  fs::create_directories(dir);
  if (c.setup) c.setup(dir);
  const auto before = snapshot(dir);
  const auto around = snapshot(pass.root, dir);
  std::vector<std::string> argv = {pass.bin};
  for (std::string a : c.argv) {
    for (std::size_t p; (p = a.find("{D}")) != std::string::npos;) a.replace(p, 3, dir.string());
    argv.push_back(a);
  }
  const fs::path log = pass.logs / ("case_" + std::to_string(index) + ".log");
  const Spawned s = spawn(argv, dir, log, pass.env);
  Result r;
  r.code = s.code;
  r.seconds = s.seconds;
  r.message = read_all(log);
  const auto after = snapshot(dir);
  const auto around_after = snapshot(pass.root, dir);

  for (const auto& [path, state] : before) {
    const auto it = after.find(path);
    if (it == after.end() || it->second != state) {
      r.data_lost = true;
      r.why += " changed: " + path + ";";
    }
  }
  if (around_after != around) {
    r.escape = true;
    for (const auto& [path, state] : around_after)
      if (!around.count(path) || around.at(path) != state) r.why += " outside: " + path + ";";
  }
  r.injection = has_marker(pass.root);

  const bool crash_text = r.message.find("terminate called") != std::string::npos ||
                          r.message.find("Segmentation fault") != std::string::npos ||
                          r.message.find("Aborted") != std::string::npos;
  if (s.timed_out) {
    r.outcome = Outcome::kHung;
  } else if (s.code < 0 || s.code == 134 || s.code == 139 || crash_text) {
    r.outcome = Outcome::kCrashed;
  } else if (c.expect == Expect::kAccept) {
    r.outcome = s.code == 0 ? Outcome::kAccepted : Outcome::kRefusedValid;
  } else if (s.code == 0) {
    r.outcome = Outcome::kSilent;
  } else {
    r.outcome = Outcome::kClean;
    for (const std::string& w : c.words)
      if (!contains(r.message, w)) {
        r.outcome = Outcome::kUnclear;
        r.why += " missing word: " + w + ";";
      }
    if (const char* raw = raw_library_text(r.message)) {
      r.outcome = Outcome::kUnclear;
      r.why += std::string(" raw text: ") + raw + ";";
    }
    // A refusal leaves nothing behind: no new file (a folder made empty is tolerated).
    for (const auto& [path, state] : after)
      if (!c.may_write && !before.count(path) && state != "dir" &&
          fs::path(path).filename() != ".run.lock") {
        r.outcome = Outcome::kUnclear;
        r.why += " left: " + path + ";";
      }
  }
  if (r.outcome == Outcome::kClean || r.outcome == Outcome::kAccepted) {
    if (!r.data_lost && !r.escape && !r.injection) {
      std::error_code ec;
      fs::remove_all(dir, ec);
      fs::remove(log, ec);
    }
  }
  return r;
}

// ---------------------------------------------------------------------------------------------
// The inputs the cases start from.

std::string source(const std::string& rel) {
  return read_all(fs::path(REPOSETWIN_SOURCE_DIR) / rel);
}

const std::string& tiny() {
  static const std::string t = source("data/loop/tiny_scene.toml");
  return t;
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t p = text.find(from);
  if (p != std::string::npos) text.replace(p, from.size(), to);
  return text;
}

const char* kCampaign = R"(name = "h"
scene = "tiny.toml"
seeds = [1]
[[case]]
name = "a"
overrides = { "contacts.rock-rock.rolling_friction" = 0.1 }
)";

const char* kCalibration = R"(name = "hc"
scene = "tiny.toml"
seeds = [1]
[calibration]
key = ["contacts.rock-rock.rolling_friction"]
target_deg = 30.0
mu_r_range = [0.05, 0.4]
)";

const char* kDesign = R"(scene = "tiny.toml"
mu_r = 0.2
seeds = [7001]
[[test]]
id = "t1"
mass_kg = 0.006
)";

const char* kIndex = R"(title = "h"
budget_cpu_hours = 1.0
[[item]]
name = "a"
paper = "p"
kind = "campaign"
file = "camp.toml"
reductions = "none"
)";

const char* kSheet = R"(id,role,scene,mass_kg,W_mm,set:contacts.rock-rock.friction,angle_deg
t1,calibrate,tiny.toml,0.006,20,0.5,30
t2,validate,tiny.toml,0.006,20,0.5,31
)";

const char* kTests = "id,mass_kg,angle_deg\nt1,0.006,31\nt2,0.006,32\n";
const char* kSieve = "sieve_mm,passing_percent\n3.0,0\n3.5,50\n4.0,100\n";

std::string dump_text(const std::string& count, const std::string& rows,
                      const std::string& columns = "id x y z radius",
                      const std::string& step = "0") {
  return "ITEM: TIMESTEP\n" + step + "\nITEM: NUMBER OF ATOMS\n" + count +
         "\nITEM: BOX BOUNDS pp pp pp\n-1 1\n-1 1\n-1 1\nITEM: ATOMS " + columns + "\n" + rows;
}

// A cone of grains a pile measure can read: `n` grains of radius 1.5 mm [m].
std::string cone_rows(int n) {
  std::ostringstream s;
  int id = 1;
  for (int k = 0; id <= n; ++k)
    for (int i = -k; i <= k && id <= n; ++i, ++id)
      s << id << " " << 0.003 * i << " " << 0.001 * (id % 3) << " " << 0.0015 + 0.003 * (6 - k)
        << " 0.0015\n";
  return s.str();
}

// A finished run folder with its photographs, made once by the test; its photographs, final
// snapshot and the folder itself are the valid inputs the cases start from.
fs::path g_base_run;

// The setup of the common inputs, written into every case's folder (cheap: a few small files).
void base_inputs(const fs::path& d) {
  write(d / "tiny.toml", tiny());
  write(d / "camp.toml", kCampaign);
  write(d / "cal.toml", kCalibration);
  write(d / "design.toml", kDesign);
  write(d / "index.toml", kIndex);
  write(d / "sheet.csv", kSheet);
  write(d / "tests.csv", kTests);
  write(d / "sieve.csv", kSieve);
  for (const char* f : {"side_az000.png", "side_az000.json", "top.png", "top.json"}) {
    const std::string name =
        std::string(f).rfind("side", 0) == 0 ? "side" + std::string(f).substr(10) : f;
    fs::copy_file(g_base_run / "images" / f, d / name);
  }
  fs::copy_file(g_base_run / "final.vtp", d / "grains.vtp");
}

// ---------------------------------------------------------------------------------------------
// The table.

Setup with(Setup more) {
  return [more](const fs::path& d) {
    base_inputs(d);
    if (more) more(d);
  };
}

std::vector<std::string> words(std::initializer_list<std::string> w) { return w; }

// What a non-regular or unusable input can be, made at `p` (the case's folder is `d`).
struct InputKind {
  std::string name;
  std::function<void(const fs::path& d, const fs::path& p)> make;
  bool absolute;  // the argument is a fixed path (a device), not `p`
  std::string path;
};

std::vector<InputKind> input_kinds() {
  return {
      {"symlink_to_fifo",
       [](const fs::path& d, const fs::path& p) {
         fifo(d / "the_fifo");
         link_to(p, d / "the_fifo");
       },
       false, ""},
      {"dangling_symlink",
       [](const fs::path& d, const fs::path& p) { link_to(p, d / "gone" / "nothing"); }, false, ""},
      {"symlink_loop",
       [](const fs::path& d, const fs::path& p) {
         link_to(p, p.string() + ".b");
         link_to(p.string() + ".b", p);
         (void)d;
       },
       false, ""},
      {"dev_full", [](const fs::path&, const fs::path&) {}, true, "/dev/full"},
      {"dev_urandom", [](const fs::path&, const fs::path&) {}, true, "/dev/urandom"},
      {"symlink_to_dir",
       [](const fs::path& d, const fs::path& p) {
         fs::create_directories(d / "a_dir");
         link_to(p, d / "a_dir");
       },
       false, ""},
      {"sparse_2GB", [](const fs::path&, const fs::path& p) { sparse(p, std::uintmax_t{2} << 30); },
       false, ""},
      {"empty", [](const fs::path&, const fs::path& p) { write(p, ""); }, false, ""},
  };
}

// One input position of one command: the argument vector with "@" where the input goes.
struct InputSlot {
  std::string command, label, file;  // file: the input's name in the case folder
  std::vector<std::string> argv;
};

std::vector<InputSlot> input_slots() {
  const std::vector<std::string> lim = {"--max-particles", "1"};
  auto plus = [](std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  return {
      {"run", "scene", "in.toml", {"run", "@", "-o", "out", "--no-images", "-q"}},
      {"run",
       "psd_file",
       "in.csv",
       {"run", "tiny.toml", "-o", "out", "--no-images", "-q", "--set", "sample.psd_file=@"}},
      {"campaign", "file", "in.toml", plus({"campaign", "@", "-o", "out"}, lim)},
      {"calibrate", "file", "in.toml", plus({"calibrate", "@", "-o", "out"}, lim)},
      {"calibrate", "tests", "in.csv",
       plus({"calibrate", "--tests", "@", "--scene", "tiny.toml", "-o", "out"}, lim)},
      {"calibrate", "sieve", "in.csv",
       plus({"calibrate", "--tests", "tests.csv", "--scene", "tiny.toml", "--sieve", "@", "-o",
             "out"},
            lim)},
      {"calibrate", "scene", "in.toml",
       plus({"calibrate", "--tests", "tests.csv", "--scene", "@", "-o", "out"}, lim)},
      {"timestep", "scene", "in.toml", plus({"timestep", "@", "-o", "out"}, lim)},
      {"export", "scene", "in.toml", {"export", "@", "-o", "out"}},
      {"export",
       "initial_state",
       "in.vtp",
       {"export", "tiny.toml", "-o", "out", "--initial-state", "@"}},
      {"measure", "side", "in.png", {"measure", "@", "--mm-per-px", "0.5"}},
      {"measure", "second_side", "in.png", {"measure", "side.png", "--side", "@"}},
      {"measure", "top", "in.png", {"measure", "side.png", "--top", "@"}},
      {"measure", "camera", "in.json", {"measure", "side.png", "--camera", "@"}},
      {"measure",
       "top_camera",
       "in.json",
       {"measure", "side.png", "--top", "top.png", "--top-camera", "@"}},
      {"measure-particles", "dump", "in.dump", {"measure-particles", "@", "--scene", "tiny.toml"}},
      {"measure-particles",
       "scene",
       "in.toml",
       {"measure-particles", "grains.vtp", "--scene", "@"}},
      {"loop", "data", "in.csv", plus({"loop", "@", "-o", "out"}, lim)},
      {"loop-synth", "design", "in.toml", plus({"loop-synth", "@", "-o", "out"}, lim)},
      {"paper", "index", "in.toml", plus({"paper", "@", "-o", "out"}, lim)},
      {"report", "lab_photo", "in.png", {"report", "run", "--lab-photo", "@", "-o", "rep"}},
      {"render", "camera", "in.json", {"render", "run", "--camera", "@", "--force"}},
  };
}

void with_run(const fs::path& d, const std::string& name = "run") {
  copy_tree(g_base_run, d / name);
}

std::vector<Case> build_cases() {
  std::vector<Case> cases;
  auto add = [&](Case c) { cases.push_back(std::move(c)); };

  // --- F1. run --set: numbers TOML reads but a person would not write, and near-numbers.
  {
    const std::vector<std::string> keys = {
        "sample.mass_kg",     "numerics.time_step_s",     "contacts.rock-rock.friction",
        "container.height_m", "procedure.lift_speed_m_s", "scene.seed",
        "numerics.threads"};
    const std::vector<std::string> values = {"0x10",  "0o7",   "0b1",  "1_0",
                                             "1e999", "0x1p3", "1..2", "1e"};
    for (const std::string& k : keys)
      for (const std::string& v : values)
        add({"run",
             "set " + k + "=" + v,
             Expect::kRefuse,
             with(nullptr),
             {"run", "tiny.toml", "-o", "out", "--no-images", "-q", "--set", k + "=" + v},
             words({k, v})});
  }

  // --- F2. loop sheet cells: every kind of number column with spellings no sheet should hold.
  {
    const std::vector<std::pair<std::string, std::string>> cols = {
        {"mass_kg", "0.006"},
        {"W_mm", "20"},
        {"set:contacts.rock-rock.friction", "0.5"},
        {"angle_deg", "30"}};
    const std::vector<std::string> values = {"0x10",
                                             "1_0",
                                             "0b1",
                                             "inf",
                                             "nan",
                                             "1e999",
                                             "\"1,5\"",
                                             "0.5x",
                                             "$(touch INJECTED)",
                                             "0.5;touch INJECTED",
                                             "-0.5",
                                             "\xef\xbc\x91"};
    for (std::size_t c = 0; c < cols.size(); ++c)
      for (const std::string& v : values) {
        const std::string row_from = "t1,calibrate,tiny.toml,0.006,20,0.5,30";
        std::vector<std::string> cells = {"t1", "calibrate", "tiny.toml", "0.006",
                                          "20", "0.5",       "30"};
        cells[3 + c] = v;
        std::string row;
        for (const std::string& x : cells) row += (row.empty() ? "" : ",") + x;
        const std::string shown = v.front() == '"' ? v.substr(1, v.size() - 2) : v;
        const std::string col = cols[c].first;
        add({"loop",
             "sheet " + col + "=" + v,
             Expect::kRefuse,
             with([row_from, row](const fs::path& d) {
               write(d / "bad.csv", replaced(kSheet, row_from, row));
             }),
             {"loop", "bad.csv", "-o", "out", "--max-particles", "1"},
             words({"bad.csv", col.rfind("set:", 0) == 0 ? col.substr(4) : col, shown})});
      }
  }

  // --- F3. calibrate's test sheet and sieve sheet cells.
  {
    const std::vector<std::string> values = {"0x10",  "1_0", "inf", "nan",
                                             "1e999", "-1",  "7,5", " 1x"};
    for (const std::string& v : values) {
      const std::string cell = v == "7,5" ? "\"7,5\"" : v;
      add({"calibrate",
           "tests mass_kg=" + v,
           Expect::kRefuse,
           with([cell](const fs::path& d) {
             write(d / "bad.csv", "id,mass_kg,angle_deg\nt1," + cell + ",31\nt2,0.006,32\n");
           }),
           {"calibrate", "--tests", "bad.csv", "--scene", "tiny.toml", "-o", "out",
            "--max-particles", "1"},
           words({"bad.csv", "mass_kg"})});
      add({"calibrate",
           "tests angle_deg=" + v,
           Expect::kRefuse,
           with([cell](const fs::path& d) {
             write(d / "bad.csv", "id,mass_kg,angle_deg\nt1,0.006," + cell + "\nt2,0.006,32\n");
           }),
           {"calibrate", "--tests", "bad.csv", "--scene", "tiny.toml", "-o", "out",
            "--max-particles", "1"},
           words({"bad.csv", "angle_deg"})});
      add({"calibrate",
           "sieve passing=" + v,
           Expect::kRefuse,
           with([cell](const fs::path& d) {
             write(d / "bad.csv", "sieve_mm,passing_percent\n3.0,0\n3.5," + cell + "\n4.0,100\n");
           }),
           {"calibrate", "--tests", "tests.csv", "--scene", "tiny.toml", "--sieve", "bad.csv", "-o",
            "out", "--max-particles", "1"},
           words({"bad.csv", "passing"})});
      add({"calibrate",
           "sieve mm=" + v,
           Expect::kRefuse,
           with([cell](const fs::path& d) {
             write(d / "bad.csv", "sieve_mm,passing_percent\n3.0,0\n" + cell + ",50\n4.0,100\n");
           }),
           {"calibrate", "--tests", "tests.csv", "--scene", "tiny.toml", "--sieve", "bad.csv", "-o",
            "out", "--max-particles", "1"},
           words({"bad.csv", "sieve"})});
    }
  }

  // --- F4. malformed TOML in every TOML file a command reads.
  {
    struct Kind {
      std::string command;
      const std::string* base;
      std::vector<std::string> argv;  // "@": the file
    };
    static const std::string campaign = kCampaign, calibration = kCalibration, design = kDesign,
                             index = kIndex;
    const std::vector<Kind> kinds = {
        {"run", &tiny(), {"run", "@", "-o", "out", "--no-images", "-q"}},
        {"timestep", &tiny(), {"timestep", "@", "-o", "out", "--max-particles", "1"}},
        {"export", &tiny(), {"export", "@", "-o", "out"}},
        {"measure-particles", &tiny(), {"measure-particles", "grains.vtp", "--scene", "@"}},
        {"campaign", &campaign, {"campaign", "@", "-o", "out", "--max-particles", "1"}},
        {"calibrate", &calibration, {"calibrate", "@", "-o", "out", "--max-particles", "1"}},
        {"loop-synth", &design, {"loop-synth", "@", "-o", "out", "--max-particles", "1"}},
        {"paper", &index, {"paper", "@", "-o", "out", "--max-particles", "1"}},
    };
    const std::vector<std::pair<std::string, std::function<std::string(const std::string&)>>>
        breaks = {
            {"cut_in_string", [](const std::string& b) { return b + "\nzz = \"never ends\n"; }},
            {"invalid_utf8", [](const std::string& b) { return b + "\n# \xc3\x28 \xff\n"; }},
            {"nul_byte", [](const std::string& b) { return b + std::string("\nzz = 1\0", 8); }},
            {"deep_arrays",
             [](const std::string& b) { return b + "\nzz = " + std::string(100000, '[') + "\n"; }},
            {"deep_tables",
             [](const std::string& b) {
               std::string s = b + "\nzz = ";
               for (int i = 0; i < 5000; ++i) s += "{a=";
               return s + "1" + std::string(5000, '}') + "\n";
             }},
            {"key_1MB",
             [](const std::string& b) { return b + "\n" + std::string(1 << 20, 'k') + " = 1\n"; }},
            {"table_then_array", [](const std::string& b) { return b + "\n[zz]\n[[zz]]\n"; }},
            {"date_value",
             [](const std::string& b) { return b + "\nzz = 1979-05-27T07:32:00Z\n"; }},
        };
    for (const Kind& k : kinds)
      for (const auto& [bname, make] : breaks) {
        const std::string text = make(*k.base);
        std::vector<std::string> argv = k.argv;
        for (std::string& a : argv)
          if (a == "@") a = "bad.toml";
        add({k.command, "toml " + bname, Expect::kRefuse,
             with([text](const fs::path& d) { write(d / "bad.toml", text); }), argv,
             words({"bad.toml"})});
      }
  }

  // --- F5. JSON: camera sidecars, a calibration record, a run's records.
  {
    const std::vector<std::pair<std::string, std::string>> bad_json = {
        {"empty", ""},
        {"object", "{}"},
        {"array", "[]"},
        {"null", "null"},
        {"string", "\"x\""},
        {"deep", std::string(100000, '[')},
        {"cut", "{\"camera\": {\"intrinsics\": "},
        {"nan_literal", "{\"camera\": NaN}"},
        {"number_1e400", "{\"camera\": 1e400}"},
        {"bad_utf8", "{\"camera\": \"\xff\xfe\"}"},
        {"bom", "\xef\xbb\xbf{}"},
        {"nul", std::string("{\"a\":1}\0", 8)},
    };
    for (const auto& [name, text] : bad_json) {
      const std::string t = text;
      add({"measure",
           "camera json " + name,
           Expect::kRefuse,
           with([t](const fs::path& d) { write(d / "cam.json", t); }),
           {"measure", "side.png", "--camera", "cam.json"},
           words({"cam.json"})});
      add({"measure",
           "top camera json " + name,
           Expect::kRefuse,
           with([t](const fs::path& d) { write(d / "cam.json", t); }),
           {"measure", "side.png", "--top", "top.png", "--top-camera", "cam.json"},
           words({"cam.json"})});
      add({"render",
           "camera json " + name,
           Expect::kRefuse,
           with([t](const fs::path& d) {
             with_run(d);
             write(d / "cam.json", t);
           }),
           {"render", "run", "--camera", "cam.json", "--force"},
           words({"cam.json"})});
      add({"report",
           "calibration.json " + name,
           Expect::kRefuse,
           with([t](const fs::path& d) { write(d / "cal" / "calibration.json", t); }),
           {"report", "cal"},
           words({"calibration.json"})});
      add({"report",
           "run_state.json " + name,
           Expect::kRefuse,
           with([t](const fs::path& d) {
             with_run(d);
             write(d / "run" / "run_state.json", t);
           }),
           {"report", "run"},
           words({"run_state.json"}),
           true});
      add({"report",
           "result.json " + name,
           Expect::kRefuse,
           with([t](const fs::path& d) {
             with_run(d);
             write(d / "run" / "result.json", t);
           }),
           {"report", "run"},
           words({"result.json"}),
           true});
    }
    // Calibration records with the right syntax and the wrong shape.
    const std::vector<std::pair<std::string, std::string>> cal = {
        {"status_only", R"({"status": "calibrated"})"},
        {"unknown_status", R"({"status": "great", "target": {"angle_deg": 30}, "mu_r": 0.1})"},
        {"mu_r_string", R"({"status": "calibrated", "target": {"angle_deg": 30}, "mu_r": "0.1"})"},
        {"no_interval", R"({"status": "calibrated", "target": {"angle_deg": 30}, "mu_r": 0.1})"},
        {"no_target", R"({"status": "calibrated", "mu_r": null})"},
    };
    for (const auto& [name, text] : cal) {
      const std::string t = text;
      add({"report",
           "calibration.json " + name,
           Expect::kRefuse,
           with([t](const fs::path& d) { write(d / "cal" / "calibration.json", t); }),
           {"report", "cal"},
           words({"calibration.json"})});
    }
  }

  // --- F6. inputs that are not regular files of a sane size, at every input of every command.
  for (const InputSlot& slot : input_slots())
    for (const InputKind& kind : input_kinds()) {
      const std::string file = slot.file;
      const auto make = kind.make;
      const bool needs_run = slot.argv.size() > 1 && (slot.argv[1] == "run");
      std::vector<std::string> argv = slot.argv;
      const std::string arg = kind.absolute ? kind.path : file;
      for (std::string& a : argv) {
        if (a == "@") a = arg;
        if (a == "sample.psd_file=@") a = "sample.psd_file=" + arg;
      }
      add({slot.command, slot.label + " is " + kind.name, Expect::kRefuse,
           with([file, make, needs_run](const fs::path& d) {
             if (needs_run) with_run(d);
             make(d, d / file);
           }),
           argv, words({arg})});
    }

  // --- F7. outputs that are not folders or files the command may write.
  {
    struct OutSlot {
      std::string command, label;
      std::vector<std::string> argv;  // "@": the output
      bool is_folder;
      std::string input;  // one of the command's inputs, for "output = input"
    };
    const std::vector<OutSlot> outs = {
        {"run", "--out", {"run", "tiny.toml", "-o", "@", "--no-images", "-q"}, true, "tiny.toml"},
        {"campaign",
         "--out",
         {"campaign", "camp.toml", "-o", "@", "--max-particles", "1"},
         true,
         "camp.toml"},
        {"campaign",
         "--cache",
         {"campaign", "camp.toml", "-o", "out", "--cache", "@", "--max-particles", "1"},
         true,
         "camp.toml"},
        {"calibrate",
         "--out",
         {"calibrate", "cal.toml", "-o", "@", "--max-particles", "1"},
         true,
         "cal.toml"},
        {"timestep",
         "--out",
         {"timestep", "tiny.toml", "-o", "@", "--max-particles", "1"},
         true,
         "tiny.toml"},
        {"export", "--out", {"export", "tiny.toml", "-o", "@"}, true, "tiny.toml"},
        {"loop",
         "--out",
         {"loop", "sheet.csv", "-o", "@", "--max-particles", "1"},
         true,
         "sheet.csv"},
        {"loop",
         "--cache",
         {"loop", "sheet.csv", "-o", "out", "--cache", "@", "--max-particles", "1"},
         true,
         "sheet.csv"},
        {"loop-synth",
         "--out",
         {"loop-synth", "design.toml", "-o", "@", "--max-particles", "1"},
         true,
         "design.toml"},
        {"loop-synth",
         "--cache",
         {"loop-synth", "design.toml", "-o", "out", "--cache", "@", "--max-particles", "1"},
         true,
         "design.toml"},
        {"paper",
         "--out",
         {"paper", "index.toml", "-o", "@", "--max-particles", "1"},
         true,
         "index.toml"},
        {"report", "--out", {"report", "run", "-o", "@"}, true, "run/result.json"},
        {"measure", "--overlay", {"measure", "side.png", "--overlay", "@"}, false, "side.png"},
        {"measure",
         "--top-overlay",
         {"measure", "side.png", "--top", "top.png", "--top-overlay", "@"},
         false,
         "top.png"},
        {"loop-synth",
         "--truth",
         {"loop-synth", "design.toml", "-o", "out", "--truth", "@", "--max-particles", "1"},
         false,
         "design.toml"},
    };
    struct OutKind {
      std::string name, path;
      Setup make;
      bool file_only;
    };
    const std::vector<OutKind> kinds = {
        {"fifo", "o_fifo", [](const fs::path& d) { fifo(d / "o_fifo"); }, false},
        {"dev_full", "/dev/full", nullptr, false},
        {"dev_null", "/dev/null", nullptr, false},
        {"users_file", "notes.txt", [](const fs::path& d) { write(d / "notes.txt", "mine\n"); },
         false},
        {"under_a_file", "notes.txt/sub",
         [](const fs::path& d) { write(d / "notes.txt", "mine\n"); }, false},
        {"the_input", "", nullptr, false},
        {"empty_path", "", nullptr, false},
        {"link_out_of_folder", "o_link",
         [](const fs::path& d) {
           link_to(d / "o_link", d.parent_path() / "outside" / "target.png");
         },
         true},
        {"a_folder", "o_dir", [](const fs::path& d) { fs::create_directories(d / "o_dir"); }, true},
    };
    for (const OutSlot& o : outs)
      for (const OutKind& k : kinds) {
        if (k.file_only && o.is_folder) continue;
        const std::string path = k.name == "the_input" ? o.input : k.path;
        const Setup make = k.make;
        const bool needs_run = o.command == "report";
        std::vector<std::string> argv = o.argv;
        for (std::string& a : argv)
          if (a == "@") a = path;
        add({o.command, o.label + " is " + k.name, Expect::kRefuse,
             with([make, needs_run](const fs::path& d) {
               if (needs_run) with_run(d);
               if (make) make(d);
             }),
             argv, words({path.empty() ? o.label : path})});
      }
  }

  // --- F7b. symlinks inside a run folder that lead out of it.
  for (const char* spot : {"images", "frames", "report"}) {
    const std::string s = spot;
    auto setup = with([s](const fs::path& d) {
      with_run(d);
      fs::create_directories(d.parent_path() / "outside" / ("dir_" + s));
      fs::remove_all(d / "run" / s);
      link_to(d / "run" / s, d.parent_path() / "outside" / ("dir_" + s));
    });
    add({"run",
         "--force over " + s + " link",
         Expect::kRefuse,
         setup,
         {"run", "tiny.toml", "-o", "run", "--force", "--no-images", "-q"},
         words({s})});
    add({"run",
         "--resume over " + s + " link",
         Expect::kRefuse,
         setup,
         {"run", "tiny.toml", "-o", "run", "--resume", "--no-images", "-q"},
         words({s})});
    add({"render",
         "render over " + s + " link",
         Expect::kRefuse,
         setup,
         {"render", "run", "--force", "--views", "1", "--width", "64", "--height", "64"},
         words({s})});
    add({"report",
         "report over " + s + " link",
         Expect::kRefuse,
         setup,
         {"report", "run", "--force"},
         words({s})});
  }

  // --- F8. numeric options: spellings CLI11 converts, or ranges it does not check. Each base
  // command is valid and stops short of a simulation when the option is taken (a plan limit, a
  // run already photographed), so an option accepted shows as a refusal that does not name it,
  // or as exit 0.
  {
    struct Opt {
      std::string command, option;
      std::vector<std::string> before;  // the command's arguments before the option
      char kind;                        // 'i' integer, 'f' float
      bool needs_run = false;
    };
    const std::vector<std::string> tiny_hours = {"--max-hours", "0.0000001"};
    const std::vector<std::string> one = {"--max-particles", "1"};
    auto cat = [](std::vector<std::string> a, const std::vector<std::string>& b) {
      a.insert(a.end(), b.begin(), b.end());
      return a;
    };
    const std::vector<std::string> run_base = {"run", "tiny.toml", "-o", "out", "--no-images"};
    const std::vector<std::string> campaign = cat({"campaign", "camp.toml", "-o", "out"}, one);
    const std::vector<std::string> calibrate = cat({"calibrate", "cal.toml", "-o", "out"}, one);
    const std::vector<std::string> timestep = cat({"timestep", "tiny.toml", "-o", "out"}, one);
    const std::vector<std::string> loop = cat({"loop", "sheet.csv", "-o", "out"}, one);
    const std::vector<std::string> synth = {"loop-synth", "design.toml", "-o", "out"};
    const std::vector<std::string> paper = cat({"paper", "index.toml", "-o", "out"}, one);
    const std::vector<Opt> opts = {
        {"run", "--threads", cat(run_base, one), 'i'},
        {"run", "--max-particles", cat(run_base, tiny_hours), 'i'},
        {"run", "--max-hours", cat(run_base, one), 'f'},
        {"render", "--views", {"render", "run"}, 'i', true},
        {"render", "--width", {"render", "run"}, 'i', true},
        {"render", "--height", {"render", "run"}, 'i', true},
        {"render", "--camera-height", {"render", "run"}, 'f', true},
        {"campaign", "--workers", campaign, 'i'},
        {"campaign", "--views", campaign, 'i'},
        {"campaign", "--max-hours", campaign, 'f'},
        {"calibrate", "--workers", calibrate, 'i'},
        {"calibrate", "--views", calibrate, 'i'},
        {"timestep", "--workers", timestep, 'i'},
        {"timestep", "--tolerance", timestep, 'f'},
        {"measure", "--mm-per-px", {"measure", "side.png", "--no-overlay"}, 'f'},
        {"measure",
         "--top-mm-per-px",
         {"measure", "side.png", "--top", "top.png", "--no-overlay"},
         'f'},
        {"loop", "--max-effects", loop, 'i'},
        {"loop", "--refit-follow-ups", loop, 'i'},
        {"loop", "--max-pours", loop, 'i'},
        {"loop", "--grid-extensions", loop, 'i'},
        {"loop", "--probe-scalings", loop, 'i'},
        {"loop", "--workers", loop, 'i'},
        {"loop", "--width", loop, 'i'},
        {"loop", "--height", loop, 'i'},
        {"loop", "--views", loop, 'i'},
        {"loop", "--min-t", loop, 'f'},
        {"loop", "--min-delta-chi2", loop, 'f'},
        {"loop", "--mu-max", loop, 'f'},
        {"loop-synth", "--workers", cat(synth, one), 'i'},
        {"loop-synth", "--max-particles", cat(synth, tiny_hours), 'i'},
        {"paper", "--workers", paper, 'i'},
        {"paper", "--views", paper, 'i'},
        {"export", "--seed", {"export", "tiny.toml", "-o", "out"}, 'i'},
        {"report", "--lab-mm-per-px", {"report", "run", "--lab-photo", "side.png"}, 'f', true},
    };
    const std::vector<std::string> ints = {"0x10", "1e1", "-1", "99999999999999999999", "\xd9\xa3"};
    const std::vector<std::string> floats = {"0x1p3", "inf", "nan", "1e999", "1,5"};
    for (const Opt& o : opts)
      for (const std::string& v : (o.kind == 'i' ? ints : floats)) {
        std::vector<std::string> argv = o.before;
        argv.push_back(o.option);
        argv.push_back(v);
        const bool needs_run = o.needs_run;
        add({o.command, o.option + " " + v, Expect::kRefuse, with([needs_run](const fs::path& d) {
               if (needs_run) with_run(d);
             }),
             argv, words({o.option, v})});
      }
    // Lists.
    struct ListOpt {
      std::string command, option;
      std::vector<std::string> before;
      std::vector<std::string> values;
    };
    const std::vector<ListOpt> lists = {
        {"loop",
         "--mu-grid",
         loop,
         {"0.1,,0.2", "0.1,0x1p-2", "0.1,inf", "0.2,0.1", "0.1;0.2", "0.1,0.1"}},
        {"loop",
         "--seeds",
         loop,
         {"1,0x2", "1,,2", "1,1", "1,-2", "1,99999999999999999999", "1.0,2"}},
        {"loop",
         "--mu-range",
         cat(loop, {"--mu-range-reason", "r"}),
         {"0.1,0x1", "0.1,inf", "nan,0.2", "0.1", "0.1,0.2,0.3", "0.1,,"}},
        {"timestep", "--fractions", timestep, {"0x1p-2", "inf", "nan", "-0.1", "0", "1e999"}},
        {"timestep",
         "--seeds",
         timestep,
         {"1,1", "0x1", "-1", "1.5", "99999999999999999999", "1,,2"}},
        {"measure",
         "--flank-band",
         {"measure", "side.png", "--no-overlay"},
         {"0x1p-3,0.8", "0.2,0x1p-1", "inf,0.8", "0.2", "0.2,0.5,0.8", "0.2,nan"}},
        {"measure",
         "--roi",
         {"measure", "side.png", "--no-overlay"},
         {"0x10,0,300,170", "1e1,0,300,170", "0,0,10", "0,0,10,10,10", "0,0,-10,10", "0,0,10,0"}},
        {"calibrate",
         "--mu-r-range",
         cat({"calibrate", "--tests", "tests.csv", "--scene", "tiny.toml", "-o", "out"}, one),
         {"0.1 0x1p-2", "0.1 inf", "nan 0.2", "0.1 0.1", "0.1 1e999"}},
    };
    for (const ListOpt& o : lists)
      for (const std::string& v : o.values) {
        std::vector<std::string> argv = o.before;
        argv.push_back(o.option);
        std::istringstream parts(v);  // "a b": two arguments
        for (std::string part; parts >> part;) argv.push_back(part);
        add({o.command, o.option + " " + v, Expect::kRefuse, with(nullptr), argv,
             words({o.option})});
      }
  }

  // --- F9. valid inputs under hostile names: accepted, nothing run from a name, nothing
  // written elsewhere.
  {
    const std::vector<std::string> names = {"it's",
                                            "a;touch INJECTED;b",
                                            "$(touch INJECTED)",
                                            "`touch INJECTED`",
                                            "sp a  ce",
                                            "new\nline",
                                            "\xc3\xbcn\xc3\xaf-\xe6\xb5\x8b",
                                            "a|b&c>d",
                                            "%s%n%x",
                                            "'\"both\"'",
                                            "tab\there",
                                            "bad\xff\xfeutf8"};
    for (std::size_t i = 0; i < names.size(); ++i) {
      const std::string n = names[i];
      const std::string tag = "name " + std::to_string(i);
      add({"measure",
           tag + " (folder)",
           Expect::kAccept,
           with([n](const fs::path& d) {
             fs::create_directories(d / n);
             fs::copy_file(d / "side.png", d / n / "side.png");
             fs::copy_file(d / "side.json", d / n / "side.json");
           }),
           {"measure", n + "/side.png"},
           {}});
      add({"measure",
           tag + " (file)",
           Expect::kAccept,
           with([n](const fs::path& d) {
             fs::copy_file(d / "side.png", d / (n + ".png"));
             fs::copy_file(d / "side.json", d / (n + ".json"));
           }),
           {"measure", n + ".png"},
           {}});
      add({"export", tag, Expect::kAccept, with(nullptr), {"export", "tiny.toml", "-o", n}, {}});
      add({"run",
           tag,
           Expect::kAccept,
           with(nullptr),
           {"run", "tiny.toml", "-o", n, "--no-images", "-q"},
           {}});
      add({"report",
           tag,
           Expect::kAccept,
           with([n](const fs::path& d) { with_run(d, n); }),
           {"report", n},
           {}});
      add({"measure-particles",
           tag,
           Expect::kAccept,
           with([n](const fs::path& d) { fs::copy_file(d / "grains.vtp", d / (n + ".vtp")); }),
           {"measure-particles", n + ".vtp", "--scene", "tiny.toml"},
           {}});
      add({"campaign",
           tag + " as a case name",
           Expect::kRefuse,
           with([n](const fs::path& d) {
             std::string esc;
             for (char c : n) {
               if (c == '"' || c == '\\') esc += '\\';
               if (c == '\n') {
                 esc += "\\n";
                 continue;
               }
               if (c == '\t') {
                 esc += "\\t";
                 continue;
               }
               esc += c;
             }
             write(d / "bad.toml", replaced(kCampaign, "name = \"a\"", "name = \"" + esc + "\""));
           }),
           {"campaign", "bad.toml", "-o", "out", "--max-particles", "1"},
           words({"bad.toml", "name~bad.toml:5:"})});
    }
  }

  // --- F10. particle dumps.
  {
    const std::vector<std::pair<std::string, std::string>> dumps = {
        {"count_hex", dump_text("0x10", cone_rows(16))},
        {"count_exponent", dump_text("1e2", cone_rows(60))},
        {"count_trailing_junk", dump_text("60abc", cone_rows(60))},
        {"timestep_word", dump_text("60", cone_rows(60), "id x y z radius", "abc")},
        {"count_huge", dump_text("99999999", cone_rows(1))},
        {"count_negative", dump_text("-5", cone_rows(1))},
        {"one_grain", dump_text("1", cone_rows(1))},
        {"grains_at_one_point", dump_text("3",
                                          "1 0 0 0.0015 0.0015\n2 0 0 0.0015 0.0015\n"
                                          "3 0 0 0.0015 0.0015\n")},
        {"radius_zero", dump_text("1", "1 0 0 0.0015 0\n")},
        {"x_hex", dump_text("1", "1 0x1p-3 0 0.0015 0.0015\n")},
        {"x_inf", dump_text("1", "1 inf 0 0.0015 0.0015\n")},
        {"no_radius_column", dump_text("1", "1 0 0 0.0015\n", "id x y z")},
        {"no_timestep", "ITEM: NUMBER OF ATOMS\n1\nITEM: ATOMS id x y z radius\n1 0 0 0 1\n"},
        {"line_of_zeros", std::string(1 << 20, '\0')},
    };
    for (const auto& [name, text] : dumps) {
      const std::string t = text;
      add({"measure-particles",
           "dump " + name,
           Expect::kRefuse,
           with([t](const fs::path& d) { write(d / "bad.dump", t); }),
           {"measure-particles", "bad.dump", "--scene", "tiny.toml"},
           words({"bad.dump"})});
    }
    add({"measure-particles",
         "dump a 2 GB line",
         Expect::kRefuse,
         with([](const fs::path& d) {
           write(d / "bad.dump", "ITEM: TIMESTEP\n");
           fs::resize_file(d / "bad.dump", std::uintmax_t{2} << 30);
         }),
         {"measure-particles", "bad.dump", "--scene", "tiny.toml"},
         words({"bad.dump"})});
  }

  // --- F11. the command line itself.
  {
    const std::vector<std::vector<std::string>> argvs = {
        {""},
        {"--"},
        {"run", "--set", "=1"},
        {"run", "--set", ".=1"},
        {"run", "--set", "sample..mass_kg=1"},
        {"run", "--set", "sample.mass_kg==1"},
        {"run", "tiny.toml", "-o", "out", "--set", "sample.mass_kg=" + std::string(100000, '1')},
        {"run", std::string(5000, 'p') + ".toml"},
        {"run", "tiny.toml", "-o", "out", "--set", "sample.psd_file=$(touch INJECTED).csv"},
        {"keys", "--markdown", "--campaign", "extra"},
        {"report"},
        {"measure"},
        {"loop"},
        {"paper", "--only", "nosuch_item", "--list"},
        {"export", "tiny.toml", "-o", "out", "--set", "sample.mass_kg=0x10"},
    };
    for (std::size_t i = 0; i < argvs.size(); ++i) {
      const std::string cmd = argvs[i][0].empty() || argvs[i][0] == "--" ? "(none)" : argvs[i][0];
      add({cmd, "argv " + std::to_string(i), Expect::kRefuse, with(nullptr), argvs[i], {}});
    }
  }

  // --- F12. campaign files with values the TOML reads but a campaign cannot use.
  {
    const std::vector<std::pair<std::string, std::string>> camps = {
        {"seed_negative", replaced(kCampaign, "seeds = [1]", "seeds = [-1]")},
        {"seed_float", replaced(kCampaign, "seeds = [1]", "seeds = [1.0]")},
        {"seed_string", replaced(kCampaign, "seeds = [1]", "seeds = [\"1\"]")},
        {"seeds_empty", replaced(kCampaign, "seeds = [1]", "seeds = []")},
        {"seed_overflow", replaced(kCampaign, "seeds = [1]", "seeds = [9223372036854775808]")},
        {"scene_dev_zero", replaced(kCampaign, "tiny.toml", "/dev/zero")},
        {"scene_empty", replaced(kCampaign, "\"tiny.toml\"", "\"\"")},
        {"scene_outside", replaced(kCampaign, "tiny.toml", "../outside/none.toml")},
        {"override_table", replaced(kCampaign, "= 0.1 }", "= { a = 1 } }")},
        {"no_cases", replaced(kCampaign,
                              "[[case]]\nname = \"a\"\noverrides = { "
                              "\"contacts.rock-rock.rolling_friction\" = 0.1 }\n",
                              "")},
    };
    for (const auto& [name, text] : camps) {
      const std::string t = text;
      add({"campaign",
           "campaign " + name,
           Expect::kRefuse,
           with([t](const fs::path& d) { write(d / "bad.toml", t); }),
           {"campaign", "bad.toml", "-o", "out", "--max-particles", "1"},
           words({"bad.toml~scene"})});
    }
    // Plans above the limits on commands that simulate, loop-synth included.
    add({"loop-synth",
         "plan above the limits",
         Expect::kRefuse,
         with(nullptr),
         {"loop-synth", "design.toml", "-o", "out", "--max-particles", "10"},
         words({"--yes", "particles"})});
  }
  return cases;
}

std::string one_line(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s.size() > 300 ? s.substr(0, 300) + "..." : s;
}

std::string csv_field(const std::string& s) {
  std::string q = "\"";
  for (char c : one_line(s)) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

// The run folder every run-folder case copies: a tiny run with its photographs (about 5 s).
fs::path make_base_run(const Pass& pass) {
  const fs::path d = pass.root.parent_path() / "base";
  fs::create_directories(d);
  write(d / "tiny.toml", tiny());
  const Spawned s =
      spawn({pass.bin, "run", "tiny.toml", "-o", "run", "-q"}, d, d / "log", pass.env);
  EXPECT_EQ(s.code, 0) << read_all(d / "log");
  fs::remove(d / "run" / ".run.lock");
  return d / "run";
}

TEST(HostilePass, EveryCaseRefusedCleanlyOrAcceptedWithoutHarm) {
  char top_template[] = "/tmp/reposetwin_hostile_XXXXXX";
  ASSERT_NE(mkdtemp(top_template), nullptr);
  const fs::path top = top_template;
  Pass pass;
  pass.root = top / "cases";
  pass.logs = top / "logs";
  pass.bin = REPOSETWIN_BIN;
  fs::create_directories(pass.root / "home");
  fs::create_directories(pass.root / "tmp");
  fs::create_directories(pass.root / "outside");
  write(pass.root / "outside" / "target.png", "a user's file outside the case folders\n");
  fs::create_directories(pass.logs);
  for (char** e = environ; *e; ++e) {
    const std::string v = *e;
    if (v.rfind("HOME=", 0) == 0 || v.rfind("TMPDIR=", 0) == 0 || v.rfind("OMPI_", 0) == 0 ||
        v.rfind("PMIX_", 0) == 0)
      continue;
    pass.env.push_back(v);
  }
  pass.env.push_back("HOME=" + (pass.root / "home").string());
  pass.env.push_back("TMPDIR=" + (pass.root / "tmp").string());
  g_base_run = make_base_run(pass);

  const std::vector<Case> cases = build_cases();
  std::map<std::string, std::array<int, static_cast<std::size_t>(Outcome::kCount) + 3>> by_cmd;
  std::array<int, static_cast<std::size_t>(Outcome::kCount) + 3> total{};
  std::ostringstream csv, faults;
  csv << "command,case,expect,exit,outcome,data_lost,path_escape,injection,seconds,why,message\n";
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    const Result r = run_case(pass, c, static_cast<int>(i));
    auto& row = by_cmd[c.command];
    for (auto* a : {&row, &total}) {
      ++(*a)[static_cast<std::size_t>(r.outcome)];
      (*a)[kOutcomeNames.size() + 0] += r.data_lost;
      (*a)[kOutcomeNames.size() + 1] += r.escape;
      (*a)[kOutcomeNames.size() + 2] += r.injection;
    }
    const char* oc = kOutcomeNames[static_cast<std::size_t>(r.outcome)];
    char secs[32];
    std::snprintf(secs, sizeof secs, "%.2f", r.seconds);
    csv << csv_field(c.command) << "," << csv_field(c.name) << ","
        << (c.expect == Expect::kAccept ? "accept" : "refuse") << "," << r.code << "," << oc << ","
        << r.data_lost << "," << r.escape << "," << r.injection << "," << secs << ","
        << csv_field(r.why) << "," << csv_field(r.message) << "\n";
    const bool fault = (r.outcome != Outcome::kClean && r.outcome != Outcome::kAccepted) ||
                       r.data_lost || r.escape || r.injection;
    if (fault)
      faults << "  [" << c.command << "] " << one_line(c.name) << ": " << oc << " (exit " << r.code
             << ")" << (r.data_lost ? " DATA LOST" : "") << (r.escape ? " PATH ESCAPE" : "")
             << (r.injection ? " INJECTION" : "") << ";" << one_line(r.why) << " | "
             << one_line(r.message) << "\n";
    // A marker found once would be blamed on every later case.
    walk(pass.root, [](const fs::path& p) {
      std::error_code ec;
      if (p.filename() == "INJECTED") fs::remove(p, ec);
    });
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::ostringstream table;
  const auto line = [&](const std::string& name, const auto& a) {
    int tried = 0;
    for (std::size_t k = 0; k < kOutcomeNames.size(); ++k) tried += a[k];
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "| %-18s | %5d | %7d | %8d | %7d | %6d | %4d | %7d | %8d | %9d | %11d | %9d |\n",
                  name.c_str(), tried, a[0], a[6], a[1], a[2], a[3], a[4], a[5], a[7], a[8], a[9]);
    table << buf;
  };
  table << "| command            | tried | refused | accepted | unclear | silent | hung | crashed "
           "| refused  | data lost | path escape | injection |\n"
        << "|                    |       | cleanly | (valid)  |         |        |      |         "
           "| valid    |           |             |           |\n"
        << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [cmd, a] : by_cmd) line(cmd, a);
  line("all", total);
  std::cout << "\nHostile pass: " << cases.size() << " cases in " << static_cast<int>(wall)
            << " s\n"
            << table.str();
  if (!faults.str().empty()) std::cout << "Faults:\n" << faults.str();
  if (const char* out = std::getenv("REPOSETWIN_HOSTILE_CSV")) {
    write(out, csv.str());
    write(std::string(out) + ".table.md", table.str());
  }

  EXPECT_GE(cases.size(), 400u);
  EXPECT_EQ(total[static_cast<std::size_t>(Outcome::kUnclear)], 0) << faults.str();
  EXPECT_EQ(total[static_cast<std::size_t>(Outcome::kSilent)], 0);
  EXPECT_EQ(total[static_cast<std::size_t>(Outcome::kHung)], 0);
  EXPECT_EQ(total[static_cast<std::size_t>(Outcome::kCrashed)], 0);
  EXPECT_EQ(total[static_cast<std::size_t>(Outcome::kRefusedValid)], 0);
  EXPECT_EQ(total[kOutcomeNames.size() + 0], 0) << "data lost";
  EXPECT_EQ(total[kOutcomeNames.size() + 1], 0) << "path escape";
  EXPECT_EQ(total[kOutcomeNames.size() + 2], 0) << "injection";
  if (!HasFailure()) {
    std::error_code ec;
    fs::remove_all(top, ec);
  } else {
    std::cout << "Cases with faults kept in " << top << "\n";
  }
}

}  // namespace
