#include "report_html.h"

#include <algorithm>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "viewer_host.h"

namespace semrec::cli {
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

std::string Text(const nlohmann::json& j, const char* key) {
  if (!j.contains(key)) return "";
  const auto& v = j.at(key);
  return v.is_string() ? v.get<std::string>() : v.dump();
}

double Number(const nlohmann::json& j, const char* key) {
  return j.contains(key) && j.at(key).is_number() ? j.at(key).get<double>()
                                                  : 0.0;
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

}  // namespace

HtmlReportResult WriteHtmlReport(const fs::path& out_dir, bool pictures) {
  const fs::path json_path = out_dir / "report.json";
  nlohmann::json report;
  try {
    report = nlohmann::json::parse(ReadTextFile(json_path));
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(json_path, std::string("not valid JSON: ") + e.what());
  }
  HtmlReportResult result;
  std::vector<std::pair<std::string, std::string>> figures;  // file, caption
  if (!pictures) {
    result.no_pictures_reason =
        "pictures were turned off (--no-report-pictures)";
  } else if (const std::string why = ViewerUnavailableReason(); !why.empty()) {
    result.no_pictures_reason = why;
  } else {
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
        result.no_pictures_reason = error;
        break;
      }
    }
  }
  result.pictures = static_cast<int>(figures.size());
  // The viewer's class colours, for the legend (what OpenUSD read, as a bonus
  // check).
  nlohmann::json class_colors = nlohmann::json::object();
  if (fs::is_regular_file(out_dir / "report" / "viewer.json")) {
    try {
      const auto viewer = nlohmann::json::parse(
          ReadTextFile(out_dir / "report" / "viewer.json"));
      if (viewer.contains("classColors")) class_colors = viewer["classColors"];
    } catch (const std::exception&) {
    }
  }

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
      Escape(Text(report, "input")), Number(report, "frames"),
      Number(report, "processed_frames"), Number(report, "segmented_frames"),
      Number(report, "resumed_frames"),
      report.contains("skipped_frames") ? report["skipped_frames"].size() : 0,
      Number(report, "seconds"), Number(report, "frames_per_second"),
      Number(report, "peak_rss_mb"), Escape(Text(report, "labels")),
      Escape(report.contains("gravity") ? Text(report["gravity"], "method")
                                        : ""));

  if (report.contains("map_guidance") &&
      report["map_guidance"].value("enabled", false)) {
    const nlohmann::json& g = report["map_guidance"];
    html += fmt::format(
        "<p class=\"meta\">map guidance: {} frames segmented in full, {} in "
        "part (masks only where the map could not explain the frame), {} "
        "labelled by projection alone; {} encoder calls, {} prompts "
        "decoded</p>\n",
        Number(g, "full_frames"), Number(g, "partial_frames"),
        Number(g, "projection_frames"), Number(g, "encoder_calls"),
        Number(g, "prompts_decoded"));
  }
  html += "<h2>The scene</h2>\n";
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

  html +=
      "<h2>Classes</h2>\n<table><tr><th>class</th><th "
      "class=\"num\">objects</th></tr>\n";
  if (report.contains("objects_per_class") &&
      report["objects_per_class"].is_object()) {
    for (const auto& [cls, count] : report["objects_per_class"].items()) {
      const std::string color =
          class_colors.contains(cls) && class_colors[cls].is_string()
              ? class_colors[cls].get<std::string>()
              : "transparent";
      html += fmt::format(
          "<tr><td><span class=\"swatch\" "
          "style=\"background:{}\"></span>{}</td>"
          "<td class=\"num\">{}</td></tr>\n",
          Escape(color), Escape(cls), count.dump());
    }
  }
  html += fmt::format("</table><p>{} people tracked.</p>\n",
                      Number(report, "people"));

  html +=
      "<h2>Objects</h2>\n<table><tr><th "
      "class=\"num\">id</th><th>class</th><th>kind</th>"
      "<th class=\"num\">vertices</th><th class=\"num\">triangles</th>"
      "<th class=\"num\">frames seen</th><th>class votes</th></tr>\n";
  if (report.contains("scene") && report["scene"].is_array()) {
    for (const auto& o : report["scene"]) {
      std::string votes;
      if (o.contains("class_votes") && o["class_votes"].is_array()) {
        for (const auto& v : o["class_votes"]) {
          if (v.is_array() && v.size() == 2 && v[0].is_string() &&
              v[1].is_number()) {
            votes += fmt::format("{}{} {:.2f}", votes.empty() ? "" : ", ",
                                 v[0].get<std::string>(), v[1].get<double>());
          }
        }
      }
      html += fmt::format(
          "<tr><td class=\"num\">{}</td><td>{}</td><td>{}</td><td "
          "class=\"num\">{}</td>"
          "<td class=\"num\">{}</td><td "
          "class=\"num\">{}</td><td>{}</td></tr>\n",
          Number(o, "id"), Escape(Text(o, "class")), Escape(Text(o, "kind")),
          Number(o, "vertices"), Number(o, "triangles"),
          Number(o, "frames_seen"), Escape(votes));
    }
  }
  html += "</table>\n";

  html +=
      "<h2>Time per stage</h2>\n<table><tr><th>stage</th><th "
      "class=\"num\">s/frame</th>"
      "<th></th></tr>\n";
  if (report.contains("seconds_per_frame") &&
      report["seconds_per_frame"].is_object()) {
    std::vector<std::pair<std::string, double>> stages;
    double total = 0;
    for (const auto& [stage, s] : report["seconds_per_frame"].items()) {
      if (!s.is_number()) continue;
      stages.emplace_back(stage, s.get<double>());
      total += s.get<double>();
    }
    std::sort(stages.begin(), stages.end(),
              [](const auto& a, const auto& b) { return a.second > b.second; });
    for (const auto& [stage, s] : stages) {
      const double share = total > 0 ? s / total : 0.0;
      html += fmt::format(
          "<tr><td>{}</td><td class=\"num\">{:.3f}</td><td><span class=\"bar\" "
          "style=\"width:{:.0f}px\"></span> {:.0f}%</td></tr>\n",
          Escape(stage), s, 300 * share, 100 * share);
    }
  }
  html += "</table>\n";

  // Overlays: up to 8, evenly spread over the recording.
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
  html += "<h2>Segmentation overlays</h2>\n";
  if (overlays.empty()) {
    html += "<p class=\"note\">No overlays (--no-overlays).</p>\n";
  } else {
    html += "<div class=\"strip\">";
    const size_t shown = std::min<size_t>(8, overlays.size());
    for (size_t i = 0; i < shown; ++i) {
      const std::string& file = overlays[i * overlays.size() / shown];
      html += fmt::format("<a href=\"{0}\"><img src=\"{0}\" alt=\"{0}\"></a>",
                          Escape(file));
    }
    html += fmt::format("</div><p class=\"meta\">{} of {} in overlay/</p>\n",
                        shown, overlays.size());
  }

  html += "<h2>Models</h2>\n<ul>\n";
  if (report.contains("models") && report["models"].is_array()) {
    for (const auto& m : report["models"]) {
      html += fmt::format("<li>{} (<code>{}</code>)</li>\n",
                          Escape(Text(m, "name")), Escape(Text(m, "file")));
    }
  }
  html += fmt::format(
      "</ul>\n<p class=\"meta\">semrec {}; options: {}</p>\n</body></html>\n",
      Escape(Text(report, "version")), Escape(Text(report, "options")));
  WriteTextFileAtomic(out_dir / "report.html", html);
  return result;
}

}  // namespace semrec::cli
