#include "experiments/report/page_check.hpp"

#include <regex>

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

}  // namespace

std::string to_string(PageProblemKind kind) {
  switch (kind) {
    case PageProblemKind::kAbsoluteLink: return "absolute link";
    case PageProblemKind::kMissingFile: return "missing file";
    case PageProblemKind::kRawJson: return "raw JSON";
    case PageProblemKind::kAbsolutePath: return "absolute path in text";
    case PageProblemKind::kAbsoluteScript: return "absolute path in a gnuplot script";
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
  return out;
}

}  // namespace reposetwin::experiments::report
