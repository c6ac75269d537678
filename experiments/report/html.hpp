// HTML pages of the reports: one page skeleton, one table and one figure, rendered from mustache
// templates (templates.hpp) with kainjow::mustache.
//
// Design note. C++ builds plain typed data (a Table of Cells, Figures, a Page of sections) and
// never writes markup; the layout lives in the templates, and mustache escapes every value, so
// a case name or a file path cannot break the page. A section is one template rendered on its
// own data, with the shared partials {{> table}} and {{> figure}} available to it; the page
// skeleton (head, style, title) then places the rendered sections in order. Values that are
// themselves rendered by a template (a section, a table caption) are the only ones inserted
// unescaped.
#pragma once

#include <kainjow/mustache.hpp>
#include <string>
#include <vector>

namespace reposetwin::experiments::report {

namespace mustache = kainjow::mustache;

struct Link {
  std::string href;
  std::string label;
};

/// One table cell: its parts in reading order (bold, code, text, small, then a note on its own
/// line, then links). Empty parts are left out.
struct Cell {
  Cell() = default;
  Cell(std::string t) : text(std::move(t)) {}  // NOLINT: a plain text cell reads best implicit
  Cell(const char* t) : text(t) {}             // NOLINT
  std::string bold;
  std::string code;
  std::string text;
  std::string small;
  std::string note;
  std::vector<Link> links;
  bool left = false;  // left-aligned in a table of numbers
};

struct TableRow {
  std::vector<Cell> cells;
  bool shaded = false;  // set apart (a prediction among calibrations)
};

/// A row of two left-aligned cells: a name and its value in words.
inline TableRow text_row(const std::string& key, const std::string& value) {
  Cell k(key), v(value);
  k.left = v.left = true;
  return {{k, v}};
}

struct Table {
  std::vector<std::string> header;
  std::vector<TableRow> rows;
  std::string caption_html;  // rendered by a template (render()); "" = no caption
  bool numeric = false;      // cells right-aligned unless Cell::left
};

struct Figure {
  std::string src;
  std::string caption;
  int width = 0;  // [px]; 0 = the image's own
};

/// A page: its title and heading, and its sections (each rendered by render()) in order.
struct Page {
  std::string title;
  std::string heading;
  std::vector<std::string> sections;
};

/// One picture to be shown beside others at one scale.
struct ScaledImage {
  int width_px = 0;        // [px]
  double mm_per_px = 0.0;  // its scale at the pile axis [mm/px], > 0
};

/// The common scale [mm/px] at which `images` are shown side by side so that one mm is as many
/// page pixels in each: the coarsest of their own scales (none is enlarged past its pixels), or
/// coarser still so that the widest on the page is at most `max_width_px`.
double beside_scale(const std::vector<ScaledImage>& images, double max_width_px);

/// An image's width on the page at the common scale `common` [px].
inline double page_width(const ScaledImage& image, double common) {
  return image.width_px * image.mm_per_px / common;
}

mustache::data to_data(const Table& t);
mustache::data to_data(const Figure& f);
mustache::data to_data(const std::vector<Figure>& fs);

/// A string value, or false when empty (mustache treats "" as true in a section).
mustache::data text_or_false(const std::string& s);

/// Renders `tmpl` on `d` with the shared partials. Throws std::logic_error for a broken template.
std::string render(const std::string& tmpl, mustache::data d);

/// The whole HTML document of a page.
std::string render_page(const Page& page);

}  // namespace reposetwin::experiments::report
