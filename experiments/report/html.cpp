#include "experiments/report/html.hpp"

#include <algorithm>
#include <stdexcept>

#include "experiments/report/templates.hpp"

namespace reposetwin::experiments::report {

mustache::data text_or_false(const std::string& s) {
  return s.empty() ? mustache::data(false) : mustache::data(s);
}

namespace {

mustache::data to_data(const Cell& c) {
  mustache::data d;
  for (const auto& [key, value] : {std::pair{"bold", &c.bold}, std::pair{"code", &c.code},
                                   std::pair{"text", &c.text}, std::pair{"small", &c.small},
                                   std::pair{"note", &c.note}})
    d.set(key, text_or_false(*value));
  mustache::data links(mustache::data::type::list);
  for (const Link& l : c.links) {
    mustache::data x;
    x.set("href", l.href);
    x.set("label", l.label);
    links.push_back(x);
  }
  d.set("links", links);
  d.set("left", c.left);
  return d;
}

}  // namespace

mustache::data to_data(const Table& t) {
  mustache::data d;
  mustache::data header(mustache::data::type::list);
  for (const std::string& h : t.header) header.push_back(h);
  mustache::data rows(mustache::data::type::list);
  for (const TableRow& r : t.rows) {
    mustache::data cells(mustache::data::type::list);
    for (const Cell& c : r.cells) cells.push_back(to_data(c));
    mustache::data row;
    row.set("cells", cells);
    row.set("shaded", r.shaded);
    rows.push_back(row);
  }
  d.set("header", header);
  d.set("rows", rows);
  d.set("caption_html", text_or_false(t.caption_html));
  d.set("numeric", t.numeric);
  return d;
}

double beside_scale(const std::vector<ScaledImage>& images, double max_width_px) {
  double common = 0.0;
  for (const ScaledImage& im : images)
    common = std::max({common, im.mm_per_px, im.width_px * im.mm_per_px / max_width_px});
  return common;
}

mustache::data to_data(const Figure& f) {
  mustache::data d;
  d.set("src", f.src);
  d.set("caption", f.caption);
  d.set("width", f.width > 0 ? mustache::data(std::to_string(f.width)) : mustache::data(false));
  return d;
}

mustache::data to_data(const std::vector<Figure>& fs) {
  mustache::data list(mustache::data::type::list);
  for (const Figure& f : fs) list.push_back(to_data(f));
  return list;
}

std::string render(const std::string& tmpl, mustache::data d) {
  mustache::mustache m{tmpl};
  if (!m.is_valid()) throw std::logic_error("report template: " + m.error_message());
  d.set("table", mustache::partial([] { return std::string(templates::kTable); }));
  d.set("figure", mustache::partial([] { return std::string(templates::kFigure); }));
  std::string out = m.render(d);
  if (!m.is_valid()) throw std::logic_error("report template: " + m.error_message());
  return out;
}

std::string render_page(const Page& page) {
  mustache::data d;
  d.set("title", page.title);
  d.set("heading", page.heading);
  mustache::data sections(mustache::data::type::list);
  for (const std::string& s : page.sections) sections.push_back(s);
  d.set("sections", sections);
  return render(templates::kPage, d);
}

}  // namespace reposetwin::experiments::report
