#include "experiments/report/gnuplot.hpp"

#include <stdexcept>

#include "experiments/io/process.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments::report {

void run_gnuplot(const std::filesystem::path& script_path, const std::string& script,
                 const std::filesystem::path& png) {
  namespace fs = std::filesystem;
  write_file_atomic(script_path.string(), script);
  std::error_code ec;
  fs::remove(png, ec);  // a stale PNG must not pass for a new plot
  // Run in the script's folder: the script names its data and PNG by file name only, so the
  // folder can be moved or committed and the script still runs there. The log is kept only when
  // gnuplot fails, for the error to point at.
  ProgramCall call;
  call.argv = {"gnuplot", script_path.filename().string()};
  call.working_dir = script_path.parent_path();
  call.log = fs::path(script_path.string() + ".log");
  try {
    run_program_checked(call, script_path.string());
  } catch (...) {
    // gnuplot opens its output before it reads the plot command: a script that fails leaves an
    // empty PNG behind, which a page must not show as a figure.
    fs::remove(png, ec);
    throw;
  }
  fs::remove(call.log, ec);
  if (fs::file_size(png, ec) == 0 || ec) {
    fs::remove(png, ec);
    throw std::runtime_error("gnuplot (" + script_path.string() + "): exited 0 but drew no " +
                             png.string());
  }
}

std::string gnuplot_string(const std::string& text) {
  std::string s = "'";
  for (char c : text) s += c == '\'' ? std::string("''") : std::string(1, c);
  return s + "'";
}

std::string png_terminal(const std::filesystem::path& png, int width, int height, bool enhanced) {
  return "set terminal pngcairo size " + std::to_string(width) + "," + std::to_string(height) +
         (enhanced ? "" : " noenhanced") + "\nset output '" + png.filename().string() + "'\n";
}

}  // namespace reposetwin::experiments::report
