#include "experiments/report/templates.hpp"

namespace reposetwin::experiments::report::templates {

// title, heading; sections: rendered HTML, in order.
const char* const kPage = R"(<!doctype html>
<html><head><meta charset='utf-8'><title>{{title}}</title>
<style>
body{font-family:sans-serif;max-width:1200px;margin:auto}
table{border-collapse:collapse;margin:6px 0}
td,th{border:1px solid #aaa;padding:3px 6px;font-size:13px}
th{background:#eee}
table.num td{text-align:right}
table.num td.l{text-align:left}
tr.shaded{background:#eef}
caption{caption-side:bottom;text-align:left;max-width:1000px}
figure{display:inline-block;margin:4px}
</style></head><body>
<h1>{{heading}}</h1>
{{#sections}}{{{.}}}
{{/sections}}</body></html>
)";

// header: [text]; rows: [{shaded, cells: [{bold, code, text, small, note, links, left}]}];
// caption_html: rendered caption or false; numeric: right-aligned cells.
const char* const kTable = R"(<table{{#numeric}} class='num'{{/numeric}}>
{{#caption_html}}<caption>{{{caption_html}}}</caption>
{{/caption_html}}<tr>{{#header}}<th>{{.}}</th>{{/header}}</tr>
{{#rows}}<tr{{#shaded}} class='shaded'{{/shaded}}>{{#cells}}<td{{#left}} class='l'{{/left}}>{{#bold}}<b>{{bold}}</b> {{/bold}}{{#code}}<code>{{code}}</code>{{/code}}{{#text}}{{text}}{{/text}}{{#small}} <small>{{small}}</small>{{/small}}{{#note}}<br><small>{{note}}</small>{{/note}}{{#links}}<a href='{{href}}'>{{label}}</a> {{/links}}</td>{{/cells}}</tr>
{{/rows}}</table>
)";

// src, caption, width (or false).
const char* const kFigure =
    R"(<figure><img src='{{src}}'{{#width}} width='{{width}}'{{/width}}><figcaption>{{caption}}</figcaption></figure>
)";

// data, code, finished.
const char* const kLoopIntro = R"(<p>Data: {{data}}<br>Code {{code}}, finished {{finished}}</p>
)";

// errors: table; mu_r, mu_r_se, seed_sd.
const char* const kLoopError = R"(<h2>Error before and after</h2>
{{#errors}}{{> table}}{{/errors}}<p>Baseline mu_r = {{mu_r}} &plusmn; {{mu_r_se}}; seed spread of one pile {{seed_sd}} deg.</p>
)";

// effects: table or false; rule, min_t, margin.
const char* const kLoopEffects = R"(<h2>Chosen effects</h2>
{{#effects}}{{> table}}{{/effects}}{{^effects}}<p>None: no candidate beat the seed noise.</p>
{{/effects}}<p>Rule: {{rule}} (min_t {{min_t}}, margin {{margin}} deg).</p>
)";

// iterations: [{n, mu_r, loo, candidates: table, stopped (or false)}].
const char* const kLoopIterations =
    R"({{#iterations}}<h3>Iteration {{n}} (mu_r {{mu_r}}; mu_r-only LOO {{loo}} deg)</h3>
{{#candidates}}{{> table}}{{/candidates}}{{#stopped}}<p>Stopped: {{stopped}}.</p>
{{/stopped}}{{/iterations}})";

// jams: [{id, n}] or false; unavailable: [{name, why}] or false.
const char* const kLoopNotes =
    R"({{#jams}}<p>Baseline pours that formed no pile and were repeated with new seeds (the lab reports none):</p>
<ul>{{#list}}<li>{{id}}: {{n}}</li>{{/list}}</ul>
{{/jams}}{{#unavailable}}<p>Unavailable candidates:</p>
<ul>{{#list}}<li>{{name}}: {{why}}</li>{{/list}}</ul>
{{/unavailable}})";

// plots: figures; residuals: table.
const char* const kLoopResiduals = R"(<h2>Residuals</h2>
{{#plots}}{{> figure}}{{/plots}}{{#residuals}}{{> table}}{{/residuals}})";

}  // namespace reposetwin::experiments::report::templates
