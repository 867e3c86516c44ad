#include "semrec/viewer/report_html.h"

#include <algorithm>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/pipeline/run_report.h"
#include "semrec/viewer/viewer_host.h"

namespace semrec::viewer {
namespace fs = std::filesystem;
namespace {

std::string Escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

constexpr const char* kStyle = R"(
body { font: 14px/1.45 sans-serif; margin: 24px auto; max-width: 1100px; color: #222; }
h1 { font-size: 20px; margin-bottom: 4px; } h2 { font-size: 16px; margin-top: 28px; }
.meta { color: #555; } table { border-collapse: collapse; } td, th { padding: 3px 10px;
border-bottom: 1px solid #ddd; text-align: left; } td.num, th.num { text-align: right; }
.pics { display: flex; gap: 12px; flex-wrap: wrap; } figure { margin: 0; }
figure img { width: 540px; border: 1px solid #ccc; } figcaption { color: #555; font-size: 12px; }
.strip { display: flex; gap: 6px; overflow-x: auto; } .strip img { height: 150px; }
.bar { background: #4a7ec9; height: 10px; display: inline-block; } .note { color: #a60; }
.swatch { display: inline-block; width: 12px; height: 12px; margin-right: 6px; border-radius: 2px; }
code { background: #f3f3f3; padding: 1px 4px; }
)";

// Renders the scene from `camera` into report/<name>; true when the picture was
// written.
bool Picture(const fs::path& scene, const fs::path& png, const fs::path& probe,
             const std::string& camera, bool class_colors, std::string* error) {
  ViewerOptions options;
  options.camera = camera;
  options.width = 1080;
  options.height = 700;
  options.panel = false;
  options.class_colors = class_colors;
  try {
    RenderScene(scene, png, probe, options);
    return true;
  } catch (const Error& e) {
    *error = e.what();
    return false;
  }
}

// The scene rendered by OpenUSD from two cameras into report/; the pictures
// written as (file, caption).
std::vector<std::pair<std::string, std::string>> ScenePictures(
    const fs::path& out_dir, bool pictures, HtmlReportResult* result) {
  std::vector<std::pair<std::string, std::string>> figures;
  if (!pictures) {
    result->no_pictures_reason =
        "pictures were turned off (--no-report-pictures)";
    return figures;
  }
  if (const std::string why = ViewerUnavailableReason(); !why.empty()) {
    result->no_pictures_reason = why;
    return figures;
  }
  const fs::path scene = out_dir / "scene.usda";
  fs::create_directories(out_dir / "report");
  const fs::path probe = out_dir / "report" / "viewer.json";
  for (const auto& [camera, caption] :
       {std::pair{"iso",
                  "from a front corner, above, in the colours fused from the "
                  "images"},
        std::pair{"top", "from above, in class colours"}}) {
    const std::string file = fmt::format("report/scene_{}.png", camera);
    const bool by_class = std::string(camera) == "top";
    std::string error;
    if (Picture(scene, out_dir / file, by_class ? probe : fs::path(), camera,
                by_class, &error)) {
      figures.emplace_back(file, caption);
    } else {
      result->no_pictures_reason = error;
      break;
    }
  }
  return figures;
}

// The viewer's class colours, for the legend (what OpenUSD read, as a bonus
// check).
nlohmann::json ViewerClassColors(const fs::path& out_dir) {
  const fs::path probe = out_dir / "report" / "viewer.json";
  if (!fs::is_regular_file(probe)) return nlohmann::json::object();
  try {
    const auto viewer = nlohmann::json::parse(ReadTextFile(probe));
    if (viewer.contains("classColors")) return viewer["classColors"];
  } catch (const std::exception&) {
  }
  return nlohmann::json::object();
}

std::string HeaderSection(const pipeline::RunReport& report,
                          const fs::path& out_dir) {
  std::string html = fmt::format(
      "<!doctype html>\n<html lang=\"en\"><head><meta "
      "charset=\"utf-8\"><title>semrec: {}"
      "</title><style>{}</style></head><body>\n",
      Escape(out_dir.filename().string()), kStyle);
  html += fmt::format("<h1>semrec run: {}</h1>\n",
                      Escape(out_dir.filename().string()));
  html += fmt::format(
      "<p class=\"meta\">input {}<br>{} frames ({} processed, {} segmented, {} "
      "resumed, {} "
      "skipped) in {:.1f} s ({:.2f} frames/s), peak memory {:.0f} MB; labels: "
      "{}; gravity: "
      "{}</p>\n",
      Escape(report.input), report.frames, report.processed_frames,
      report.segmented_frames, report.resumed_frames,
      report.skipped_frames.size(), report.seconds, report.frames_per_second,
      report.peak_rss_mb, Escape(report.labels),
      Escape(report.GravityMethod()));
  if (report.map_guidance && report.map_guidance->enabled) {
    const pipeline::MapGuidanceReport& g = *report.map_guidance;
    html += fmt::format(
        "<p class=\"meta\">map guidance: {} frames segmented in full, {} in "
        "part (masks only where the map could not explain the frame), {} "
        "labelled by projection alone; {} encoder calls, {} prompts "
        "decoded</p>\n",
        g.full_frames, g.partial_frames, g.projection_frames, g.encoder_calls,
        g.prompts_decoded);
  }
  return html;
}

std::string SceneSection(
    const std::vector<std::pair<std::string, std::string>>& figures,
    const HtmlReportResult& result, const fs::path& out_dir) {
  std::string html = "<h2>The scene</h2>\n";
  if (!figures.empty()) {
    html += "<div class=\"pics\">";
    for (const auto& [file, caption] : figures) {
      html += fmt::format(
          "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"scene {1}\"></a>"
          "<figcaption>{1} (rendered by OpenUSD)</figcaption></figure>",
          file, Escape(caption));
    }
    html += "</div>\n";
  } else {
    html += fmt::format("<p class=\"note\">No pictures: {}</p>\n",
                        Escape(result.no_pictures_reason));
  }
  html += fmt::format("<p>Explore it in 3D: <code>semrec view {}</code></p>\n",
                      Escape(out_dir.string()));
  return html;
}

std::string ClassesSection(const pipeline::RunReport& report,
                           const nlohmann::json& class_colors) {
  std::string html =
      "<h2>Classes</h2>\n<table><tr><th>class</th><th "
      "class=\"num\">objects</th></tr>\n";
  for (const auto& [cls, count] : report.objects_per_class) {
    const std::string color =
        class_colors.contains(cls) && class_colors[cls].is_string()
            ? class_colors[cls].get<std::string>()
            : "transparent";
    html += fmt::format(
        "<tr><td><span class=\"swatch\" "
        "style=\"background:{}\"></span>{}</td>"
        "<td class=\"num\">{}</td></tr>\n",
        Escape(color), Escape(cls), count);
  }
  html += fmt::format("</table><p>{} people tracked.</p>\n", report.people);
  return html;
}

std::string ObjectsSection(const pipeline::RunReport& report) {
  std::string html =
      "<h2>Objects</h2>\n<table><tr><th "
      "class=\"num\">id</th><th>class</th><th>kind</th>"
      "<th class=\"num\">vertices</th><th class=\"num\">triangles</th>"
      "<th class=\"num\">frames seen</th><th>class votes</th></tr>\n";
  for (const pipeline::ObjectRecord& o : report.scene) {
    std::string votes;
    for (const auto& [name, share] : o.class_votes) {
      votes +=
          fmt::format("{}{} {:.2f}", votes.empty() ? "" : ", ", name, share);
    }
    html += fmt::format(
        "<tr><td class=\"num\">{}</td><td>{}</td><td>{}</td><td "
        "class=\"num\">{}</td>"
        "<td class=\"num\">{}</td><td "
        "class=\"num\">{}</td><td>{}</td></tr>\n",
        o.id, Escape(o.class_name), Escape(o.kind), o.vertices, o.triangles,
        o.frames_seen, Escape(votes));
  }
  return html + "</table>\n";
}

std::string StagesSection(const pipeline::RunReport& report) {
  std::string html =
      "<h2>Time per stage</h2>\n<table><tr><th>stage</th><th "
      "class=\"num\">s/frame</th>"
      "<th></th></tr>\n";
  std::vector<std::pair<std::string, double>> stages =
      report.seconds_per_frame.Named();
  double total = 0;
  for (const auto& [stage, s] : stages) total += s;
  // Longest first; ties by name (as the stages were listed before).
  std::sort(stages.begin(), stages.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first < b.first;
  });
  for (const auto& [stage, s] : stages) {
    const double share = total > 0 ? s / total : 0.0;
    html += fmt::format(
        "<tr><td>{}</td><td class=\"num\">{:.3f}</td><td><span class=\"bar\" "
        "style=\"width:{:.0f}px\"></span> {:.0f}%</td></tr>\n",
        Escape(stage), s, 300 * share, 100 * share);
  }
  return html + "</table>\n";
}

// Overlays: up to 8, evenly spread over the recording.
std::string OverlaysSection(const fs::path& out_dir) {
  std::vector<std::string> overlays;
  std::error_code ec;
  if (fs::is_directory(out_dir / "overlay", ec)) {
    for (const auto& entry : fs::directory_iterator(out_dir / "overlay", ec)) {
      if (entry.path().extension() == ".png") {
        overlays.push_back("overlay/" + entry.path().filename().string());
      }
    }
  }
  std::sort(overlays.begin(), overlays.end());
  std::string html = "<h2>Segmentation overlays</h2>\n";
  if (overlays.empty()) {
    return html + "<p class=\"note\">No overlays (--no-overlays).</p>\n";
  }
  html += "<div class=\"strip\">";
  const size_t shown = std::min<size_t>(8, overlays.size());
  for (size_t i = 0; i < shown; ++i) {
    const std::string& file = overlays[i * overlays.size() / shown];
    html += fmt::format("<a href=\"{0}\"><img src=\"{0}\" alt=\"{0}\"></a>",
                        Escape(file));
  }
  html += fmt::format("</div><p class=\"meta\">{} of {} in overlay/</p>\n",
                      shown, overlays.size());
  return html;
}

std::string ModelsSection(const pipeline::RunReport& report) {
  std::string html = "<h2>Models</h2>\n<ul>\n";
  for (const pipeline::ModelRecord& m : report.models) {
    html += fmt::format("<li>{} (<code>{}</code>)</li>\n", Escape(m.name),
                        Escape(m.file));
  }
  html += fmt::format(
      "</ul>\n<p class=\"meta\">semrec {}; options: {}</p>\n</body></html>\n",
      Escape(report.version), Escape(report.options));
  return html;
}

}  // namespace

HtmlReportResult WriteHtmlReport(const fs::path& out_dir, bool pictures) {
  const pipeline::RunReport report =
      pipeline::ReadRunReport(out_dir / "report.json");
  HtmlReportResult result;
  const auto figures = ScenePictures(out_dir, pictures, &result);
  result.pictures = static_cast<int>(figures.size());
  std::string html = HeaderSection(report, out_dir);
  html += SceneSection(figures, result, out_dir);
  html += ClassesSection(report, ViewerClassColors(out_dir));
  html += ObjectsSection(report);
  html += StagesSection(report);
  html += OverlaysSection(out_dir);
  html += ModelsSection(report);
  WriteTextFileAtomic(out_dir / "report.html", html);
  return result;
}

}  // namespace semrec::viewer
