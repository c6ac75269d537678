#include "experiments/report/page_check.hpp"

#include <map>
#include <regex>
#include <set>

#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments::report {
namespace fs = std::filesystem;

namespace {

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

// A reference the page does not resolve on disk: another site, a mail address, inline data, an
// anchor on the same page.
bool is_external(const std::string& ref) {
  for (const char* p : {"http://", "https://", "mailto:", "data:", "#"})
    if (starts_with(ref, p)) return true;
  return false;
}

bool is_absolute(const std::string& ref) {
  return starts_with(ref, "/") || starts_with(ref, "file:") || starts_with(ref, "~") ||
         (ref.size() > 2 && std::isalpha(static_cast<unsigned char>(ref[0])) && ref[1] == ':' &&
          (ref[2] == '/' || ref[2] == '\\'));
}

// The file a reference names: the attribute's HTML entities undone (mustache escapes & and
// quotes), without its #fragment or ?query.
std::string file_part(const std::string& ref) {
  std::string s = ref.substr(0, ref.find_first_of("#?"));
  for (const auto& [entity, ch] : {std::pair{"&amp;", "&"}, std::pair{"&apos;", "'"},
                                   std::pair{"&quot;", "\""}, std::pair{"&lt;", "<"},
                                   std::pair{"&gt;", ">"}})
    for (std::size_t at; (at = s.find(entity)) != std::string::npos;)
      s.replace(at, std::string(entity).size(), ch);
  return s;
}

void check_references(const fs::path& page, const std::string& html,
                      std::vector<PageProblem>& out) {
  for (const std::string& ref : page_references(html)) {
    if (ref.empty() || is_external(ref)) continue;
    if (is_absolute(ref)) {
      out.push_back({PageProblemKind::kAbsoluteLink, page.string(), ref});
      continue;
    }
    std::error_code ec;
    if (!fs::exists(page.parent_path() / file_part(ref), ec))
      out.push_back({PageProblemKind::kMissingFile, page.string(), ref});
  }
}

void check_pre_blocks(const fs::path& page, const std::string& html,
                      std::vector<PageProblem>& out) {
  const std::regex pre(R"(<pre[^>]*>\s*([\{\[][\s\S]{0,40}))", std::regex::icase);
  for (auto it = std::sregex_iterator(html.begin(), html.end(), pre); it != std::sregex_iterator();
       ++it)
    out.push_back({PageProblemKind::kRawJson, page.string(), (*it)[1]});
}

// Paths like /work/runs/x or /home/a/b in the text (two components or more after a space, a tag
// or a bracket), outside attributes: a reader's machine has none of them.
void check_text_paths(const fs::path& page, const std::string& html,
                      std::vector<PageProblem>& out) {
  const std::string text = std::regex_replace(html, std::regex("<[^>]*>"), " ");
  const std::regex path(R"((?:^|[\s(\[])(/[A-Za-z0-9_.\-]+/[A-Za-z0-9_.\-/]+))");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), path);
       it != std::sregex_iterator(); ++it)
    out.push_back({PageProblemKind::kAbsolutePath, page.string(), (*it)[1]});
}

void check_scripts(const fs::path& dir, std::vector<PageProblem>& out) {
  const std::regex quoted(R"(['"](/[^'"]*)['"])");
  std::error_code ec;
  for (const auto& e : fs::recursive_directory_iterator(dir, ec)) {
    if (e.path().extension() != ".gp") continue;
    const std::string s = read_file(e.path().string());
    for (auto it = std::sregex_iterator(s.begin(), s.end(), quoted); it != std::sregex_iterator();
         ++it)
      out.push_back({PageProblemKind::kAbsoluteScript, e.path().string(), (*it)[1]});
  }
}

// The data files a gnuplot script reads: every quoted name ending in .dat.
std::vector<std::string> script_data(const std::string& script) {
  std::vector<std::string> out;
  const std::regex dat(R"(['"]([^'"]+\.dat)['"])");
  for (auto it = std::sregex_iterator(script.begin(), script.end(), dat);
       it != std::sregex_iterator(); ++it)
    out.push_back((*it)[1]);
  return out;
}

// The page's figures: two it shows with the same image or drawn from the same data; and every
// empty image or data file in its folder.
void check_figures(const fs::path& page, const std::string& html, std::vector<PageProblem>& out) {
  const fs::path dir = page.parent_path();
  std::map<std::string, std::string> by_image, by_data;  // content -> the first figure's name
  std::set<std::string> seen;
  for (const std::string& ref : page_references(html)) {
    if (ref.empty() || is_external(ref) || is_absolute(ref)) continue;
    const std::string name = file_part(ref);
    if (fs::path(name).extension() != ".png" || !seen.insert(name).second) continue;
    std::error_code ec;
    const fs::path png = dir / name;
    if (!fs::is_regular_file(png, ec)) continue;  // a missing file is reported already
    if (fs::file_size(png, ec) == 0) continue;  // reported with the folder's files below
    const std::string bytes = read_file(png.string());
    if (const auto [it, fresh] = by_image.emplace(bytes, name); !fresh)
      out.push_back({PageProblemKind::kSameData, page.string(), name + " shows " + it->second});
    const fs::path script = fs::path(png).replace_extension(".gp");
    if (!fs::is_regular_file(script, ec)) continue;
    std::string data;
    for (const std::string& f : script_data(read_file(script.string()))) {
      const fs::path file = script.parent_path() / f;
      if (!fs::is_regular_file(file, ec)) continue;
      data += read_file(file.string()) + "\x1f";
    }
    if (data.empty()) continue;
    if (const auto [it, fresh] = by_data.emplace(data, name); !fresh && by_image.at(bytes) == name)
      out.push_back({PageProblemKind::kSameData, page.string(),
                     name + " is drawn from the data of " + it->second});
  }
  // Every image and data file beside the page, shown or not: an empty one is a figure that
  // failed to draw, or a series written with nothing in it.
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string ext = e.path().extension().string();
    if ((ext != ".png" && ext != ".dat") || !e.is_regular_file(ec)) continue;
    const std::string name = e.path().filename().string();
    if (ext == ".png" && fs::file_size(e.path(), ec) == 0)
      out.push_back({PageProblemKind::kEmptyImage, page.string(), name});
    if (ext == ".dat" &&
        read_file(e.path().string()).find_first_not_of(" \t\r\n") == std::string::npos)
      out.push_back({PageProblemKind::kEmptyData, page.string(), name});
  }
}

}  // namespace

std::string to_string(PageProblemKind kind) {
  switch (kind) {
    case PageProblemKind::kAbsoluteLink: return "absolute link";
    case PageProblemKind::kMissingFile: return "missing file";
    case PageProblemKind::kRawJson: return "raw JSON";
    case PageProblemKind::kAbsolutePath: return "absolute path in text";
    case PageProblemKind::kAbsoluteScript: return "absolute path in a gnuplot script";
    case PageProblemKind::kEmptyImage: return "empty image";
    case PageProblemKind::kEmptyData: return "empty data file";
    case PageProblemKind::kSameData: return "two figures from the same data";
  }
  return "?";
}

std::vector<std::string> page_references(const std::string& html) {
  std::vector<std::string> refs;
  const std::regex attr(R"re((?:src|href)\s*=\s*(?:'([^']*)'|"([^"]*)"))re", std::regex::icase);
  for (auto it = std::sregex_iterator(html.begin(), html.end(), attr); it != std::sregex_iterator();
       ++it)
    refs.push_back((*it)[1].matched ? (*it)[1].str() : (*it)[2].str());
  return refs;
}

std::vector<PageProblem> page_problems(const fs::path& page) {
  const std::string html = read_file(page.string());
  std::vector<PageProblem> out;
  check_references(page, html, out);
  check_pre_blocks(page, html, out);
  check_text_paths(page, html, out);
  check_scripts(page.parent_path(), out);
  check_figures(page, html, out);
  return out;
}

}  // namespace reposetwin::experiments::report
