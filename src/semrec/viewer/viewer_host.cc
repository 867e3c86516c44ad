#include "semrec/viewer/viewer_host.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include <fmt/format.h>

#include "semrec/core/error.h"

extern char** environ;

namespace semrec::viewer {
namespace fs = std::filesystem;
namespace {

// The viewer's page and host script, and the npm packages scripts/setup
// installed; both can be moved with SEMREC_VIEWER_DIR / SEMREC_NODE_MODULES.
fs::path ViewerDir() {
  const char* env = std::getenv("SEMREC_VIEWER_DIR");
  return env != nullptr && *env != '\0' ? fs::path(env)
                                        : fs::path(SEMREC_VIEWER_DIR);
}

fs::path NodeModules() {
  const char* env = std::getenv("SEMREC_NODE_MODULES");
  return env != nullptr && *env != '\0' ? fs::path(env)
                                        : fs::path(SEMREC_NODE_MODULES);
}

// The first executable `name` on PATH; empty when there is none.
fs::path FindOnPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
    if (::access(candidate.c_str(), X_OK) == 0) {
      return candidate;
    }
  }
  return {};
}

std::vector<std::string> HostArgs(const fs::path& scene,
                                  const ViewerOptions& options) {
  std::vector<std::string> args = {
      FindOnPath("node").string(),
      (ViewerDir() / "view.mjs").string(),
      "--modules",
      NodeModules().string(),
      "--scene",
      scene.string(),
      "--port",
      std::to_string(options.port),
      "--camera",
      options.camera,
      "--size",
      fmt::format("{}x{}", options.width, options.height),
      "--timeout-s",
      std::to_string(options.timeout_s)};
  args.insert(args.end(),
              {"--panel", options.panel ? "on" : "off", "--class-colors",
               options.class_colors ? "on" : "off"});
  if (options.time) {
    args.insert(args.end(), {"--time", fmt::format("{}", *options.time)});
  }
  return args;
}

std::vector<char*> Argv(std::vector<std::string>& args) {
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return argv;
}

void RequireViewer() {
  const std::string reason = ViewerUnavailableReason();
  if (!reason.empty()) throw Error("the viewer cannot run: " + reason);
}

}  // namespace

void ViewerOptions::Check() const {
  CheckArgument(port >= 0 && port <= 65535,
                "port must be in 0..65535 (0: any free port)");
  CheckArgument(camera == "iso" || camera == "top" || camera == "front" ||
                    camera == "side",
                "camera must be iso, top, front or side, not '" + camera + "'");
  CheckArgument(width >= 64 && width <= 4096 && height >= 64 && height <= 4096,
                "picture size must be within 64..4096 pixels per side");
  CheckArgument(timeout_s > 0, "timeout_s must be > 0");
}

fs::path ResolveScene(const fs::path& input) {
  std::error_code ec;
  if (fs::is_directory(input, ec)) {
    for (const char* name : {"scene.usda", "scene.usdz", "scene.glb"}) {
      if (fs::is_regular_file(input / name, ec)) {
        return fs::absolute(input / name);
      }
    }
    throw IoError(
        input,
        "no scene.usda, scene.usdz or scene.glb in this folder (is it a "
        "`semrec run` or `semrec mesh` result?)");
  }
  if (!fs::exists(input, ec)) throw IoError(input, "no such file or folder");
  if (!fs::is_regular_file(input, ec)) {
    throw IoError(input, "not a file or a folder");
  }
  const std::string ext = input.extension().string();
  if (ext != ".usda" && ext != ".usd" && ext != ".usdc" && ext != ".usdz" &&
      ext != ".glb") {
    throw FormatError(
        input, "not a scene: expected .usda, .usd, .usdc, .usdz or .glb");
  }
  return fs::absolute(input);
}

std::string ViewerUnavailableReason() {
  std::vector<std::string> missing;
  if (FindOnPath("node").empty()) {
    missing.push_back("Node.js (node) is not on PATH");
  }
  if (!fs::is_regular_file(ViewerDir() / "view.mjs")) {
    missing.push_back("viewer files not found in " + ViewerDir().string() +
                      " (set SEMREC_VIEWER_DIR)");
  }
  for (const char* pkg : {"three", "three-usdz-loader"}) {
    if (!fs::is_regular_file(NodeModules() / pkg / "package.json")) {
      missing.push_back(
          fmt::format("npm package {} not in {} (run scripts/setup, or set "
                      "SEMREC_NODE_MODULES)",
                      pkg, NodeModules().string()));
    }
  }
  std::string reason;
  for (const std::string& m : missing) {
    reason += (reason.empty() ? "" : "; ") + m;
  }
  return reason;
}

void ServeViewer(const fs::path& scene, const ViewerOptions& options) {
  options.Check();
  RequireViewer();
  std::vector<std::string> args = HostArgs(scene, options);
  std::vector<char*> argv = Argv(args);
  ::execv(argv[0], argv.data());
  throw Error(
      fmt::format("cannot start {}: {}", args[0], std::strerror(errno)));
}

void RenderScene(const fs::path& scene, const fs::path& png,
                 const fs::path& probe_json, const ViewerOptions& options) {
  options.Check();
  RequireViewer();
  std::vector<std::string> args = HostArgs(scene, options);
  if (!png.empty()) {
    args.insert(args.end(), {"--screenshot", fs::absolute(png).string()});
  }
  if (!probe_json.empty()) {
    args.insert(args.end(), {"--probe", fs::absolute(probe_json).string()});
  }
  // The host's messages (stderr) become the error; its summary line (stdout) is
  // dropped.
  const fs::path log =
      fs::temp_directory_path() / fmt::format("semrec-view-{}.log", ::getpid());
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null",
                                   O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0600);
  std::vector<char*> argv = Argv(args);
  pid_t pid = 0;
  const int spawned =
      posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    throw Error(
        fmt::format("cannot start {}: {}", args[0], std::strerror(spawned)));
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  std::ifstream in(log);
  std::string message((std::istreambuf_iterator<char>(in)),
                      std::istreambuf_iterator<char>());
  std::error_code ec;
  fs::remove(log, ec);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  // Drop OpenUSD's harmless schema-registry chatter from the message.
  std::string filtered;
  std::stringstream lines(message);
  for (std::string line; std::getline(lines, line);) {
    if (line.find("Coding Error") != std::string::npos || line.empty()) {
      continue;
    }
    const std::string prefix = "semrec view: ";
    if (line.rfind(prefix, 0) == 0) line = line.substr(prefix.size());
    filtered += line + "\n";
  }
  while (!filtered.empty() && filtered.back() == '\n') filtered.pop_back();
  if (filtered.empty()) {
    throw IoError(scene, "the viewer failed without a message");
  }
  throw Error(filtered);  // the host's message names the scene
}

}  // namespace semrec::viewer
