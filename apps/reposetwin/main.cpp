// reposetwin: the one command-line entry point. Thin: each subcommand lives in its own
// apps/reposetwin/cmd_*.cpp and is registered in the table below.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <csignal>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "apps/reposetwin/commands.hpp"
#include "experiments/io/files.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/suggest.hpp"

namespace {

// CLI11 (2.1) reads an unknown first word as a missing subcommand; a user who typed "runn"
// wants to hear which command was meant. Returns the message, or "" when `word` is a command.
std::string unknown_command(CLI::App& app, const std::string& word) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands({})) {
    if (sub->get_name() == word) return "";
    names.push_back(sub->get_name());
  }
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  return "reposetwin: '" + word + "' is not a command" +
         reposetwin::experiments::did_you_mean(word, names, "'") + "\ncommands: " + list +
         " (reposetwin --help)";
}

// CLI11 names an option it does not know ("The following argument was not expected: --sett")
// without the one meant. The subcommand being parsed is the last one the command line names;
// every long option it and the top level take is a candidate.
std::string unknown_options(CLI::App& app, const CLI::ExtrasError& e, int argc, char** argv) {
  CLI::App* cmd = &app;
  for (int i = 1; i < argc; ++i)
    for (CLI::App* sub : cmd->get_subcommands({}))
      if (sub->get_name() == argv[i]) cmd = sub;
  std::vector<std::string> known;
  for (const CLI::App* a : {cmd, static_cast<CLI::App*>(&app)})
    for (const CLI::Option* o : a->get_options())
      for (const std::string& name : o->get_lnames()) known.push_back("--" + name);
  std::string msg = e.what();
  for (int i = 1; i < argc; ++i) {
    std::string word = argv[i];
    word = word.substr(0, word.find('='));
    if (word.rfind("--", 0) != 0 || msg.find(word) == std::string::npos) continue;
    if (std::find(known.begin(), known.end(), word) != known.end()) continue;
    const std::string where = "reposetwin" + (cmd == &app ? std::string() : " " + cmd->get_name());
    msg += "\n" + word + ": not an option of " + where +
           reposetwin::experiments::did_you_mean(word, known, "'") + " (" + where + " --help)";
  }
  return msg;
}

// An empty argument is no value anywhere on this command line: `--out ""` would fall back to a
// default folder and `--overlay ""` to the default file, each silently. Returns the message for
// the first one, naming the option it was given to, or "".
std::string empty_argument(CLI::App& app, int argc, char** argv) {
  // "-o" named as the help names it, "--out".
  const auto long_name = [&](const std::string& flag) {
    CLI::App* sub = nullptr;
    for (CLI::App* s : app.get_subcommands({}))
      if (argc > 1 && s->get_name() == argv[1]) sub = s;
    const CLI::Option* opt = sub ? sub->get_option_no_throw(flag) : nullptr;
    return opt ? opt->get_name() : flag;
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const std::size_t eq = a.find('=');
    if (a.rfind("--", 0) == 0 && eq != std::string::npos && eq + 1 == a.size())
      return "reposetwin: error: " + long_name(a.substr(0, eq)) +
             " is empty: give a value (an empty argument never stands for a default)";
    if (!a.empty()) continue;
    const std::string before = i > 1 ? argv[i - 1] : "";
    if (before.size() > 1 && before[0] == '-')
      return "reposetwin: error: " + long_name(before) +
             " is empty: give a value (an empty argument never stands for a default)";
    return "reposetwin: error: argument " + std::to_string(i) +
           " is empty; give a file, a folder or a value";
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  // A file-size limit (ulimit -f, a quota) reached mid-write kills a process with SIGXFSZ by
  // default, leaving a temporary file and no word; ignored, the write fails with EFBIG and the
  // writer names the file, as on a full disk.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"ReposeTwin: a DEM digital twin of the angle-of-repose pile test"};
  app.set_version_flag("--version", reposetwin::experiments::code_version());
  app.require_subcommand(1);
  app.footer(reposetwin::cli::exit_code_help());
  // Subcommand registry: one line per command.
  reposetwin::cli::add_run_command(app);
  reposetwin::cli::add_render_command(app);
  reposetwin::cli::add_campaign_command(app);
  reposetwin::cli::add_calibrate_command(app);
  reposetwin::cli::add_report_command(app);
  reposetwin::cli::add_timestep_command(app);
  reposetwin::cli::add_measure_command(app);
  reposetwin::cli::add_loop_command(app);
  reposetwin::cli::add_keys_command(app);
  reposetwin::cli::add_paper_command(app);
  reposetwin::cli::add_export_command(app);
  reposetwin::cli::add_measure_particles_command(app);
  if (const std::string msg = empty_argument(app, argc, argv); !msg.empty()) {
    std::cerr << msg << "\n";
    return static_cast<int>(reposetwin::cli::ExitCode::kError);
  }
  if (argc > 1 && argv[1][0] != '-') {
    if (const std::string msg = unknown_command(app, argv[1]); !msg.empty()) {
      std::cerr << msg << "\n";
      return static_cast<int>(CLI::ExitCodes::ExtrasError);
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ExtrasError& e) {
    std::cerr << unknown_options(app, e, argc, argv) << "\n";
    return e.get_exit_code();
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const reposetwin::experiments::FolderBusy& e) {
    // Refused, not waited for: a run holds its folder for hours, and a command that hangs
    // without a word is worse than one that says who holds the folder.
    std::cerr << "reposetwin: error: " << e.what() << "\n";
    return static_cast<int>(reposetwin::cli::ExitCode::kBusy);
  } catch (const std::filesystem::filesystem_error& e) {
    // The library's "filesystem error: status: ... [path]" as a sentence naming the path.
    std::cerr << "reposetwin: error: " << e.path1().string() << ": " << e.code().message();
    if (!e.path2().empty()) std::cerr << " (with " << e.path2().string() << ")";
    std::cerr << "\n";
    return static_cast<int>(reposetwin::cli::ExitCode::kError);
  } catch (const nlohmann::json::exception& e) {
    std::cerr << "reposetwin: error: a JSON record: " << reposetwin::experiments::json_error_text(e)
              << "\n";
    return static_cast<int>(reposetwin::cli::ExitCode::kError);
  } catch (const std::exception& e) {
    std::cerr << "reposetwin: error: " << e.what() << "\n";
    return static_cast<int>(reposetwin::cli::ExitCode::kError);
  }
  return reposetwin::cli::exit_code();
}
