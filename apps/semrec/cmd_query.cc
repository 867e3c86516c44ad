// `semrec query scene.usda [--class C] [--id N] [--near x,y,z --radius r]
// [--json]`.
#include <cstdio>
#include <optional>

#include <fmt/format.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "semrec/core/error.h"
#include "semrec/usd/usda_reader.h"

namespace semrec::cli {
namespace {

struct QueryArgs {
  std::string scene;
  std::string cls;
  std::optional<uint32_t> id;
  std::vector<double> near;
  double radius = 0.5;
  bool json = false;
};

void RunQuery(const QueryArgs& args) {
  CheckUsage(args.near.empty() || args.near.size() == 3, "--near takes x,y,z");
  CheckUsage(args.radius >= 0.0, "--radius must be >= 0");
  nlohmann::json out = nlohmann::json::array();
  std::string table;
  for (const usd::MeshPrim& m : usd::ReadScene(args.scene)) {
    if (!args.cls.empty() && m.label != args.cls) continue;
    if (args.id && m.instance_id != *args.id) continue;
    Eigen::AlignedBox3d box;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const auto& p : m.points) {
      box.extend(p.cast<double>());
      centroid += p.cast<double>();
    }
    if (!m.points.empty()) centroid /= static_cast<double>(m.points.size());
    if (!args.near.empty()) {
      const Eigen::Vector3d q(args.near[0], args.near[1], args.near[2]);
      if (m.points.empty() || box.exteriorDistance(q) > args.radius) continue;
    }
    out.push_back(
        {{"class", m.label},
         {"id", m.instance_id},
         {"vertices", m.points.size()},
         {"triangles", m.triangles.size()},
         {"fused_points", m.point_count},
         {"confidence", m.confidence},
         {"bounds_min", {box.min().x(), box.min().y(), box.min().z()}},
         {"bounds_max", {box.max().x(), box.max().y(), box.max().z()}},
         {"centroid", {centroid.x(), centroid.y(), centroid.z()}}});
    table += fmt::format(
        "{:<14} {:>5} {:>5.2f} {:>9} {:>9}  [{:.2f} {:.2f} {:.2f}] - [{:.2f} "
        "{:.2f} {:.2f}]"
        "  ({:.2f}, {:.2f}, {:.2f})\n",
        m.label, m.instance_id, m.confidence, m.points.size(),
        m.triangles.size(), box.min().x(), box.min().y(), box.min().z(),
        box.max().x(), box.max().y(), box.max().z(), centroid.x(), centroid.y(),
        centroid.z());
  }
  if (args.json) {
    std::printf("%s\n", out.dump(2).c_str());
    return;
  }
  std::printf("%-14s %5s %5s %9s %9s  %-38s  %s\n%s%zu objects\n", "class",
              "id", "conf", "vertices", "triangles", "bounds (m)",
              "centroid (m)", table.c_str(), out.size());
}

}  // namespace

void RegisterQuery(CLI::App& app) {
  auto args = std::make_shared<QueryArgs>();
  CLI::App* cmd = app.add_subcommand("query",
                                     "List the objects of a semrec USD scene "
                                     "(class, id, confidence = the class's "
                                     "share of the votes, vertex/triangle "
                                     "counts, bounds, centroid), optionally "
                                     "filtered.");
  cmd->add_option("scene", args->scene, "scene.usda (or static.usda)")
      ->required();
  cmd->add_option("--class", args->cls, "Only this class");
  cmd->add_option("--id", args->id, "Only this instance id");
  cmd->add_option("--near", args->near,
                  "Only objects within --radius of x,y,z (m)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--radius", args->radius, "Radius for --near (m)")
      ->capture_default_str();
  cmd->add_flag("--json", args->json, "Print JSON");
  cmd->callback([args] { RunQuery(*args); });
}

}  // namespace semrec::cli
