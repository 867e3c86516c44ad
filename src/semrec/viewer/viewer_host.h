// Runs the browser viewer (viewer/page): Node serves the page, OpenUSD
// compiled to WebAssembly reads the scene in the browser, and headless Chromium
// takes screenshots. Used by `semrec view` and by `semrec run`'s report.
#pragma once
#include <filesystem>
#include <optional>
#include <string>

namespace semrec::viewer {

struct ViewerOptions {
  /// Local port to serve on; 0 picks a free one.
  int port = 0;
  /// Headless picture: camera preset iso|top|front|side, time code (people),
  /// picture size.
  std::string camera = "iso";
  std::optional<double> time;
  int width = 1280;
  int height = 800;
  /// Show the side panel (legend, toggles) in the picture; colour objects by
  /// class.
  bool panel = true;
  bool class_colors = false;
  /// Seconds the headless browser may take to load the scene.
  int timeout_s = 120;
  void Check() const;
};

/// The scene a user named: a .usda/.usd/.usdc/.usdz/.glb file, or a result
/// folder (its scene.usda, else scene.usdz, else scene.glb). Throws
/// InvalidArgument naming the path.
std::filesystem::path ResolveScene(const std::filesystem::path& input);

/// Where the viewer's files and npm packages are, and whether Node and Chromium
/// are there; empty when all is present, else what is missing and how to get
/// it.
std::string ViewerUnavailableReason();

/// Serves the viewer for `scene` until interrupted (replaces this process with
/// Node).
[[noreturn]] void ServeViewer(const std::filesystem::path& scene,
                              const ViewerOptions& options);

/// Renders `scene` headless into `png` (when not empty) and writes what OpenUSD
/// read as JSON to `probe_json` (when not empty). Throws IoError with the
/// viewer's message when the scene cannot be loaded or the browser fails.
void RenderScene(const std::filesystem::path& scene,
                 const std::filesystem::path& png,
                 const std::filesystem::path& probe_json,
                 const ViewerOptions& options);

}  // namespace semrec::viewer
