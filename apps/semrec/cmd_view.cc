// `semrec view <result-dir|scene.usda|scene.usdz|scene.glb> [--port P]
//  [--screenshot out.png [--time T] [--camera iso|top|front|side] [--size
//  WxH]]`.
#include <cstdio>

#include <fmt/format.h>

#include "commands.h"
#include "semrec/viewer/viewer_host.h"

namespace semrec::cli {
namespace {

struct ViewArgs {
  std::string input;
  std::string screenshot;
  std::string probe;
  std::string size = "1280x800";
  double time = -1.0;
  viewer::ViewerOptions options;
};

void RunView(ViewArgs args) {
  int width = 0;
  int height = 0;
  char tail = 0;
  CheckUsage(
      std::sscanf(args.size.c_str(), "%dx%d%c", &width, &height, &tail) == 2,
      "--size takes WIDTHxHEIGHT, e.g. 1280x800");
  args.options.width = width;
  args.options.height = height;
  if (args.time >= 0.0) args.options.time = args.time;
  CheckUsage(args.options);
  const auto scene = viewer::ResolveScene(args.input);
  if (args.screenshot.empty() && args.probe.empty()) {
    viewer::ServeViewer(scene, args.options);
  }
  viewer::RenderScene(scene, args.screenshot, args.probe, args.options);
  if (!args.screenshot.empty()) fmt::print("wrote {}\n", args.screenshot);
  if (!args.probe.empty()) fmt::print("wrote {}\n", args.probe);
}

}  // namespace

void RegisterView(CLI::App& app) {
  auto* cmd = app.add_subcommand("view",
                                 "Show a scene in the browser: serves a local "
                                 "page on 127.0.0.1 where Pixar's OpenUSD "
                                 "(WebAssembly) reads the scene; objects in "
                                 "vertex or class colours, class legend, "
                                 "hover/click for class, id and size, people "
                                 "over time. With --screenshot, renders "
                                 "headless in Chromium and exits.");
  auto args = std::make_shared<ViewArgs>();
  cmd->add_option(
         "scene", args->input,
         "A result folder (its scene.usda, scene.usdz or scene.glb) or a "
         ".usda/.usd/.usdc/.usdz/.glb file")
      ->required();
  cmd->add_option("--port", args->options.port,
                  "Port on 127.0.0.1 (0: any free port)")
      ->capture_default_str();
  cmd->add_option("--screenshot", args->screenshot,
                  "Render headless into this PNG and exit (needs Chromium)");
  cmd->add_option("--time", args->time,
                  "Time code (frame) for the screenshot: where the people are "
                  "(default: first)");
  cmd->add_option("--camera", args->options.camera,
                  "Screenshot camera: iso, top, front or side")
      ->capture_default_str();
  cmd->add_option("--size", args->size, "Screenshot size WIDTHxHEIGHT")
      ->capture_default_str();
  cmd->add_flag(
      "--class-colors", args->options.class_colors,
      "Screenshot in class colours instead of the fused image colours");
  cmd->add_flag(
      "--no-panel", [args](int64_t) { args->options.panel = false; },
      "Screenshot without the side panel (legend, toggles)");
  cmd->add_option("--probe", args->probe,
                  "Write what the viewer read (objects, classes, people, time "
                  "range, up axis) "
                  "as JSON and exit");
  cmd->add_option("--timeout-s", args->options.timeout_s,
                  "Seconds the headless browser may take to load the scene")
      ->capture_default_str();
  cmd->callback([args] { RunView(*args); });
}

}  // namespace semrec::cli
