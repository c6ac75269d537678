#include "experiments/report/templates.hpp"

namespace reposetwin::experiments::report::templates {

// title, heading; sections: rendered HTML, in order.
const char* const kPage = R"(<!doctype html>
<html><head><meta charset='utf-8'><title>{{title}}</title>
<style>
body{font-family:sans-serif;max-width:1200px;margin:auto}
table{border-collapse:collapse;margin:6px 0;max-width:100%}
td,th{border:1px solid #aaa;padding:3px 6px;font-size:13px}
td code,td small,figcaption{overflow-wrap:anywhere}
img{max-width:100%}
.beside{display:flex;gap:8px;align-items:flex-start}
.beside figure{margin:0}
th{background:#eee}
table.num td{text-align:right}
table.num td.l{text-align:left}
tr.shaded{background:#eef}
caption{caption-side:bottom;text-align:left;max-width:1000px}
figure{display:inline-block;margin:4px}
.headline .angle{font-size:44px;font-weight:bold;margin:8px 0}
.note{color:#a40}
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

// built, version; dir (the folder's name: the report sits in its report/) or folders (how many).
// reason: what the run's stage record says and what is missing.
const char* const kIncompleteRun = R"(<h2>Incomplete run: no headline</h2>
<p>This run folder stopped between its stages: {{reason}}. Its files are not shown as a result; <code>reposetwin run --resume</code> finishes it.</p>
)";

const char* const kBuilt =
    R"(<p>Built {{built}} by {{version}} from {{#dir}}the folder <code>{{dir}}</code> (the one above this report){{/dir}}{{^dir}}{{folders}} folder(s){{/dir}}.</p>
)";

// photos: figures (the lab photo, then the render beside it); render: whether there is one;
// scale: the common scale in words, or false; note: why the lab photo is not shown, or false.
const char* const kLabPhoto = R"(<h2>Lab photo beside the simulated render</h2>
{{#scale}}<p>{{scale}}</p>
{{/scale}}<div class='beside'>{{#photos}}{{> figure}}{{/photos}}</div>
{{^render}}<p>(no simulated render with a measurement overlay in this folder)</p>
{{/render}}{{#note}}<p>{{note}}</p>
{{/note}})";

// plot: PNG name or false; comparison: table.
const char* const kComparison = R"(<h2>Beside the paper's Table 3</h2>
{{#plot}}<img src='{{plot}}' alt='measured against simulated angle'>
{{/plot}}{{#comparison}}{{> table}}{{/comparison}})";

// conventions: [{keyword, torque, radius, twice}]; notes: {file, text} or false.
const char* const kComparisonCaption =
    R"(Our mu_r is that of the scene's rolling model; the paper's is EDEM's. )"
    R"({{#conventions}}Ours (<code>{{keyword}}</code>): {{torque}}; lever arm {{radius}}. )"
    R"({{#twice}}For equal spheres R* = R/2, half EDEM's lever arm R, so the same torque cap )"
    R"(needs about twice EDEM's mu_r. {{/twice}}{{/conventions}})"
    R"({{#notes}}Paper (from {{file}}):{{text}}. {{/notes}})"
    R"({{^notes}}Paper: EDEM, lever arm R = contact-to-centre distance (paper data not found: )"
    R"(give --paper-data). {{/notes}})"
    R"(Angles: ours atan(2H/D) as measured (see each calibration's angle method), the paper's )"
    R"(EDEM angle a protractor on a centre slice, the lab's atan(2H/D) from a photo. )"
    R"(Predictions (shaded) run the other test at the calibrated mu_r; their mu_r interval )"
    R"(effect is the angle range at the interval's ends. Simulations count every run used.)";

// The angles plot (angles.png, made before the page: a failing gnuplot stops the report).
const char* const kAngles = R"(<h2>Angles per case</h2><img src='angles.png'>
)";

// listed: {links: [{href, label}]} (the folder's own files that list its runs) or false;
// kept: whether renders follow; renders: figures.
const char* const kNoCases = R"(<h2>Cases</h2>
<p>This folder keeps no run records (<code>cases/</code>), so the report cannot list its cases{{#listed}}; its runs are in {{#links}}<a href='{{href}}'>{{label}}</a> {{/links}}{{/listed}}.{{#kept}} The renders below were copied into this report by an earlier build, when the runs were here.{{/kept}}</p>
{{#renders}}{{> figure}}{{/renders}})";

// cases: table; renders: figures; no_renders: why there are none, or false.
const char* const kCases = R"(<h2>Cases</h2>
{{#cases}}{{> table}}{{/cases}}<h2>Renders with measurement overlays</h2>
{{#renders}}{{> figure}}{{/renders}}{{#no_renders}}<p>{{no_renders}}</p>
{{/no_renders}})";

// plot: PNG name or false; summary: table; fit: table or false; link: calibration.json.
const char* const kCalibration = R"(<h2>Calibration</h2>
{{#plot}}<img src='{{plot}}' alt='angle against mu_r: runs, monotone fit, calibrated mu_r'>
{{/plot}}{{#summary}}{{> table}}{{/summary}}{{#fit}}<h3>The fit, point by point</h3>
{{> table}}{{/fit}}<p>Every field: <a href='{{link}}'>calibration.json</a>.</p>
)";

// export: the export command, or false (no calibrated mu_r); again: the calibrate command's
// advice when there is none; report: the report command that rebuilds this page; where: the
// folder the commands are run in.
const char* const kNextSteps = R"(<h2>What next</h2>
<p>Each command is run {{where}}.</p>
<ul>{{#export}}<li>The calibrated material as a LIGGGHTS 3.8 deck (the scene, the sieve sheet and mu_r with its interval, nothing retyped): <code>{{export}}</code>; its README says what is carried and what is not.</li>
<li>The field: a field-scale deck (a stope, a dump) is not built yet; the exported deck is the lab's pile test, whose container and insertion you replace by your geometry, keeping the material lines.</li>
{{/export}}{{^export}}<li>This calibration reached no mu_r, so there is nothing to export: {{again}}</li>
{{/export}}<li>This page again, after more runs: <code>{{report}}</code>.</li></ul>
)";

// predictions: table; link: predictions.json.
const char* const kPredictions = R"(<h2>Predictions at the calibrated mu_r</h2>
{{#predictions}}{{> table}}{{/predictions}}<p>Every field: <a href='{{link}}'>predictions.json</a>.</p>
)";

// folders: [{href, dir, title}].
const char* const kFolders = R"(<h2>Folders</h2>
<ul>
{{#folders}}<li><a href='{{href}}'>{{dir}}</a> ({{title}})</li>
{{/folders}}</ul>
)";

// angle, sd (or false), measure, H_mm, D_mm, particles, views, note (or false).
const char* const kRunHeadline = R"(<div class='headline'>
<p class='angle'>{{angle}}{{#sd}} &plusmn; {{sd}}{{/sd}}&deg;</p>
<p><b>Angle of repose</b> <code>headline_angle_deg</code> = {{measure}}{{#views}} (mean of {{views}}, &plusmn; their spread){{/views}}.
H = {{H_mm}} mm, D = {{D_mm}} mm, {{particles}} particles.</p>
{{#note}}<p class='note'>{{note}}</p>
{{/note}}</div>
)";

// reason: why there is no headline; advice: what to change; particles.
const char* const kRunNoHeadline = R"(<div class='headline'>
<p class='angle'>No angle of repose</p>
<p><code>headline_angle_deg</code> is null: {{reason}}.</p>
<p>What to try: {{advice}}. {{particles}} particles in the run's world at its end; the other
measures below are of that state, not of a settled pile.</p>
</div>
)";

// warnings: [{text}]; ok: whether none applies; rules: the rules in a sentence.
const char* const kRunRepresentativeness =
    R"(<h2>Is this pile representative of the lab's test?</h2>
{{#ok}}<p>Yes, by the rules below.</p>
{{/ok}}{{^ok}}<ul class='note'>
{{#warnings}}<li>{{text}}.</li>
{{/warnings}}</ul>
{{/ok}}<p>Rules: {{rules}}. The numbers are in <code>result.json</code>'s <code>representativeness</code>.</p>
)";

// photos: figures (side overlays, then the top overlay); none: why there are no photos, or false.
const char* const kRunPhotos = R"(<h2>The twin's photographs, measured</h2>
{{#photos}}{{> figure}}{{/photos}}{{#none}}<p>{{none}}</p>
{{/none}})";

// heading; intro (or false); rows: table.
const char* const kRunTable = R"(<h2>{{heading}}</h2>
{{#intro}}<p>{{intro}}</p>
{{/intro}}{{#rows}}{{> table}}{{/rows}})";

// data, code, finished.
const char* const kLoopIntro = R"(<p>Data: {{data}}<br>Code {{code}}, finished {{finished}}</p>
)";

// errors: table; mu_r, mu_r_se, seed_sd.
const char* const kLoopError = R"(<h2>Error before and after</h2>
{{#errors}}{{> table}}{{/errors}}<p>Baseline mu_r = {{mu_r}} &plusmn; {{mu_r_se}}; seed spread of one pile {{seed_sd}} deg.</p>
)";

// effects: table or false; none: why no effect was chosen; rule, min_t, margin.
const char* const kLoopEffects = R"(<h2>Chosen effects</h2>
{{#effects}}{{> table}}{{/effects}}{{^effects}}<p>None: {{none}}</p>
{{/effects}}<p>Rule: {{rule}} (min_t {{min_t}}, margin {{margin}} deg).</p>
)";

// iterations: [{n, mu_r, loo, candidates: table, declared (or false), stopped (or false),
// refit: {text, trials: table or false} or false}].
const char* const kLoopIterations =
    R"({{#iterations}}<h3>Iteration {{n}} (mu_r {{mu_r}}; mu_r-only LOO {{loo}} deg)</h3>
{{#candidates}}{{> table}}{{/candidates}}{{#joint}}<p>Traced jointly on {{channels}}:</p>
{{> table}}{{/joint}}<p>Decision: {{decision}}.</p>
{{#declared}}<p>Declared hypothesis: {{declared}}.</p>
{{/declared}}{{#stopped}}<p>Stopped: {{stopped}}.</p>
{{/stopped}}{{#refit}}<p>{{text}}</p>
{{#trials}}{{> table}}{{/trials}}{{/refit}}{{/iterations}})";

// can, cannot: {list: [..]} or false; grid, not_traced: text or false; jams: [{id, n}] or false;
// unavailable: [{name, why}] or false.
const char* const kLoopNotes =
    R"({{#can}}<p>What this design can decide:</p>
<ul>{{#list}}<li>{{.}}</li>{{/list}}</ul>{{/can}}{{#cannot}}<p>What it cannot:</p>
<ul>{{#list}}<li>{{.}}</li>{{/list}}</ul>{{/cannot}}{{#grid}}<p>mu_r grid: {{grid}}.</p>
{{/grid}}{{#not_traced}}<p><strong>Nothing was traced</strong>: {{not_traced}}.</p>
{{/not_traced}}{{#jams}}<p>Baseline pours that formed no pile and were repeated with new seeds (the lab reports none):</p>
<ul>{{#list}}<li>{{id}}: {{n}}</li>{{/list}}</ul>
{{/jams}}{{#unavailable}}<p>Unavailable candidates:</p>
<ul>{{#list}}<li>{{name}}: {{why}}</li>{{/list}}</ul>
{{/unavailable}})";

// plots: figures; constant: a sentence (or false); residuals: table; no_pile: [text] (held-out
// tests predicted no pile, with where their pours jammed).
const char* const kLoopResiduals = R"(<h2>Residuals</h2>
{{#plots}}{{> figure}}{{/plots}}{{#constant}}<p>{{constant}}</p>
{{/constant}}{{#residuals}}{{> table}}{{/residuals}}{{#no_pile}}<p>{{.}}.</p>
{{/no_pile}})";

// pairs: [{id, scale, figures, note (or false), files: table}].
const char* const kLoopPhotos = R"(<h2>Lab and twin, like for like</h2>
<p>Per test: the lab's photo and one twin photo of the same test, each with vision's measurement drawn on it (the H and D lines, the toe line, the apex), shown at one scale, so a pile of one size is one size in both; where the lab gave no photo, the twin's alone. The twin's is the first seed's pile at the grid point nearest the final mu_r, with the effects of the model's main simulated surface.</p>
{{#pairs}}<h3>{{id}}</h3>
<p>{{scale}}</p>
{{#any_figures}}<div class='beside'>{{#figures}}{{> figure}}{{/figures}}</div>
{{/any_figures}}{{#note}}<p class='note'>{{note}}</p>
{{/note}}{{#files}}{{> table}}{{/files}}{{/pairs}})";

// index, version, built, planned, budget, within (bool); summary: table.
const char* const kPaperIntro = R"(<p>Built {{built}} by {{version}} from the paper index <code>{{index}}</code>: every table and figure of the paper beside ours. The paper's stated values are points where its text gives numbers; shape-only figures are its described trend. Ours: mean &plusmn; seed sd over the runs that formed a pile. Planned cost {{planned}} CPU-hours{{#within}}, within{{/within}}{{^within}}, ABOVE{{/within}} the budget of {{budget}} CPU-hours (run plan: particles x steps at its stated rate, one thread).</p>
{{#summary}}{{> table}}{{/summary}})";

// anchor, heading, status, reductions, paper_text (or false), trend (or false), not_run (bool),
// plot (PNG or false), ours: table or false, plan: table.
const char* const kPaperItem = R"(<h2 id='{{anchor}}'>{{heading}}</h2>
<p><b>Status:</b> {{status}}. <b>Reductions:</b> {{reductions}}</p>
{{#paper_text}}<p><b>The paper:</b> {{paper_text}}</p>
{{/paper_text}}{{#trend}}<p><b>The paper (shape only):</b> {{trend}}</p>
{{/trend}}{{#not_run}}<p class='note'>Not yet run.</p>
{{/not_run}}{{#plot}}<img src='{{plot}}' alt='{{heading}}'>
{{/plot}}{{#ours}}{{> table}}{{/ours}}{{#plan}}{{> table}}{{/plan}})";

}  // namespace reposetwin::experiments::report::templates
