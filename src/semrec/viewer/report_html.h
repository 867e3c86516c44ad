// report.html for a `semrec run` result folder: what a user looks at first.
// Built from report.json (stage timings, classes, objects, people, models),
// pictures of the scene from two angles rendered by the browser viewer
// (OpenUSD-WASM in headless Chromium), and a strip of overlays.
#pragma once
#include <filesystem>
#include <string>

namespace semrec::viewer {

struct HtmlReportResult {
  /// The pictures written (report/scene_*.png); 0 when the viewer is
  /// unavailable or failed.
  int pictures = 0;
  /// Why there are no pictures (empty when there are).
  std::string no_pictures_reason;
};

/// Writes `out_dir`/report.html (atomically) and its pictures under
/// `out_dir`/report/. Needs `out_dir`/report.json; throws IoError/FormatError
/// naming it when absent or malformed. With `pictures` false, or when the
/// viewer cannot run, the report says so instead of showing them.
HtmlReportResult WriteHtmlReport(const std::filesystem::path& out_dir,
                                 bool pictures);

}  // namespace semrec::viewer
