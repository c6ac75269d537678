#include "experiments/report/gnuplot.hpp"

#include <cstdlib>

#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments::report {

bool run_gnuplot(const std::filesystem::path& script_path, const std::string& script,
                 const std::filesystem::path& png) {
  write_file_atomic(script_path.string(), script);
  std::error_code ec;
  std::filesystem::remove(png, ec);  // a stale PNG must not pass for a new plot
  // Run in the script's folder: the script names its data and PNG by file name only, so the
  // folder can be moved or committed and the script still runs there.
  const std::string cmd = "cd '" + script_path.parent_path().string() + "' && gnuplot '" +
                          script_path.filename().string() + "' > /dev/null 2>&1";
  const bool ok = std::system(cmd.c_str()) == 0 && std::filesystem::file_size(png, ec) > 0 && !ec;
  // gnuplot opens its output before it reads the plot command: a script that fails leaves an
  // empty PNG behind, which a page must not show as a figure.
  if (!ok) std::filesystem::remove(png, ec);
  return ok;
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
