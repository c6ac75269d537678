// Checks a written report page the way a reader meets it in a copied folder or a fresh clone:
// every link and image relative and present, no path of the machine that built it, no result
// file pasted raw, and plot scripts that run where they lie.
//
// Design note. The writers are built to pass these checks (relative links, names-only gnuplot
// scripts, tables for records); this file checks the written result from outside, on the HTML
// text and the files beside it, so it holds for pages written by older code too (the committed
// reports under results/) and a test can run it over all of them. A figure is checked for what
// a reader would see: an image of zero bytes, a plot script reading an empty data file, and two
// figures of one page that show the same thing (the same image bytes, or scripts whose data
// files hold the same numbers): a figure drawn from another figure's data is not its own.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace reposetwin::experiments::report {

/// What is wrong on a page.
enum class PageProblemKind {
  kAbsoluteLink,    // a src or href that is an absolute path or a file: URL
  kMissingFile,     // a relative src or href to a file that does not exist
  kRawJson,         // a <pre> block holding JSON
  kAbsolutePath,    // an absolute file path in the page's text
  kAbsoluteScript,  // a gnuplot script beside the page naming a file by an absolute path
  kEmptyImage,      // an image beside the page is an empty file
  kEmptyData,       // a data file beside the page is empty
  kSameData,        // two figures of the page drawn from the same data (or the same image)
};

/// "absolute link", "missing file", "raw JSON", "absolute path in text", "absolute path in a
/// gnuplot script", "empty image", "empty data file", "two figures from the same data".
std::string to_string(PageProblemKind kind);

struct PageProblem {
  PageProblemKind kind;
  std::string where;  // the page (or script) the problem is in
  std::string what;   // the reference, path or first characters of the block, as written
};

/// Every src='...' / href="..." of an HTML text, in order.
std::vector<std::string> page_references(const std::string& html);

/// The problems of the page at `page`: its references (links to other pages' anchors and to
/// http(s), mailto and data URLs are not checked), its <pre> blocks and text, the gnuplot
/// scripts (*.gp) in its folder and below, and its figures (the PNGs it shows, with the data
/// files of their scripts STEM.gp beside them). Throws std::runtime_error when the page is unreadable.
std::vector<PageProblem> page_problems(const std::filesystem::path& page);

}  // namespace reposetwin::experiments::report
