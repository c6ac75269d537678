// The mustache templates of the report pages (defined in templates.cpp as raw strings, compiled
// in so a report needs no files beside the binary).
//
// Design note. The page layout lives here and nowhere else: the one skeleton (kPage: head,
// style, title, sections), the shared partials (kTable, kFigure) and one template per section.
// Each section template names the data it reads at its top; C++ (html.hpp) only fills that
// data. Data keys never reuse a partial's name ("table", "figure"): mustache looks partials up
// in the same context stack as values.
#pragma once

namespace reposetwin::experiments::report::templates {

// The page skeleton and the partials shared by every section.
extern const char* const kPage;
extern const char* const kTable;
extern const char* const kFigure;

// Sections of a run, campaign, calibration or comparison report.
extern const char* const kBuilt;
extern const char* const kIncompleteRun;
extern const char* const kLabPhoto;
extern const char* const kComparison;
extern const char* const kComparisonCaption;
extern const char* const kAngles;
extern const char* const kNextSteps;
extern const char* const kCases;
extern const char* const kNoCases;
extern const char* const kCalibration;
extern const char* const kPredictions;
extern const char* const kFolders;

// Sections of a run's one-page summary (run_summary.hpp).
extern const char* const kRunHeadline;
extern const char* const kRunNoHeadline;
extern const char* const kRunRepresentativeness;
extern const char* const kRunPhotos;
extern const char* const kRunTable;

// Sections of the paper page (reproduce/paper_page.hpp).
extern const char* const kPaperIntro;
extern const char* const kPaperItem;
// Sections of the loop's page.
extern const char* const kLoopIntro;
extern const char* const kLoopError;
extern const char* const kLoopEffects;
extern const char* const kLoopIterations;
extern const char* const kLoopNotes;
extern const char* const kLoopResiduals;
extern const char* const kLoopPhotos;

}  // namespace reposetwin::experiments::report::templates
