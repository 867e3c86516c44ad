#include "semrec/usd/usda_writer.h"

#include <cctype>
#include <set>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/usd/usda_text.h"
#include "semrec/usd/usdz.h"

namespace semrec::usd {
namespace detail {

std::string Quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) out += c;
  }
  return out + "\"";
}

std::string Num(float x) { return fmt::format("{}", x); }

std::string Header(const StageOptions& o, const std::string& extra) {
  std::string data;
  for (const auto& [key, value] : o.custom_layer_data) {
    data += fmt::format("        string {} = {}\n", SanitizeName(key),
                        Quote(value));
  }
  std::string time;
  if (o.time_codes_per_second > 0.0) {
    time = fmt::format(
        "    startTimeCode = {}\n    endTimeCode = {}\n    "
        "timeCodesPerSecond = {}\n",
        o.start_time_code, o.end_time_code, o.time_codes_per_second);
  }
  return fmt::format(
      "#usda 1.0\n(\n    defaultPrim = \"World\"\n    metersPerUnit = {}\n    "
      "upAxis = \"{}\"\n"
      "{}{}{})\n\n",
      o.meters_per_unit, o.up_axis, time,
      data.empty() ? "" : "    customLayerData = {\n" + data + "    }\n",
      extra);
}

std::string Color3(const std::array<uint8_t, 3>& c) {
  return fmt::format("({}, {}, {})", Num(c[0] / 255.0f), Num(c[1] / 255.0f),
                     Num(c[2] / 255.0f));
}

std::string SemanticsAttributes(const std::string& label,
                                const std::string& indent) {
  const std::string q = Quote(label);
  return fmt::format(
      "{0}token[] semantics:labels:class = [{1}]\n"
      "{0}string semantic:Semantics:params:semanticData = {1}\n"
      "{0}string semantic:Semantics:params:semanticType = \"class\"\n",
      indent, q);
}

}  // namespace detail

using detail::Color3;
using detail::Header;
using detail::Num;
using detail::Quote;

void StageOptions::Check() const {
  CheckArgument(up_axis == "Z" || up_axis == "Y",
                "usd: up_axis must be \"Z\" or \"Y\"");
  CheckArgument(meters_per_unit > 0.0, "usd: meters_per_unit must be > 0");
  CheckArgument(time_codes_per_second >= 0.0,
                "usd: time_codes_per_second must be >= 0");
  CheckArgument(end_time_code >= start_time_code,
                "usd: end_time_code must be >= start_time_code");
}

std::string SanitizeName(const std::string& label) {
  std::string out;
  for (unsigned char c : label) {
    out += (std::isalnum(c) || c == '_') ? static_cast<char>(c) : '_';
  }
  if (out.empty() || std::isdigit(static_cast<unsigned char>(out[0]))) {
    out = "_" + out;
  }
  return out;
}

namespace detail {

// One Mesh prim named `name` (the caller checks names for duplicates).
std::string MeshPrimText(const MeshPrim& m, const std::string& name) {
  std::string text;
  for (const auto& t : m.triangles) {
    CheckArgument(
        t[0] < m.points.size() && t[1] < m.points.size() &&
            t[2] < m.points.size(),
        "usd: mesh '" + m.label + "' has a triangle index out of range");
  }
  CheckArgument(m.normals.empty() || m.normals.size() == m.points.size(),
                "usd: normals must be empty or one per point");
  CheckArgument(
      m.vertex_colors.empty() || m.vertex_colors.size() == m.points.size(),
      "usd: vertex colours must be empty or one per point");
  Eigen::AlignedBox3f box;
  for (const auto& p : m.points) box.extend(p);
  if (m.points.empty()) box.extend(Eigen::Vector3f::Zero());
  std::string points, indices, counts, normals, colors;
  for (size_t i = 0; i < m.points.size(); ++i) {
    const auto& p = m.points[i];
    points += fmt::format("{}({}, {}, {})", i ? ", " : "", Num(p.x()),
                          Num(p.y()), Num(p.z()));
  }
  for (size_t i = 0; i < m.triangles.size(); ++i) {
    const auto& t = m.triangles[i];
    indices += fmt::format("{}{}, {}, {}", i ? ", " : "", t[0], t[1], t[2]);
    counts += i ? ", 3" : "3";
  }
  for (size_t i = 0; i < m.normals.size(); ++i) {
    const auto& n = m.normals[i];
    normals += fmt::format("{}({}, {}, {})", i ? ", " : "", Num(n.x()),
                           Num(n.y()), Num(n.z()));
  }
  for (size_t i = 0; i < m.vertex_colors.size(); ++i) {
    colors += (i ? ", " : "") + Color3(m.vertex_colors[i]);
  }
  const std::string label = Quote(m.label);
  text += fmt::format(
      "        def Mesh \"{}\" (\n"
      "            prepend apiSchemas = [\"SemanticsLabelsAPI:class\", "
      "\"SemanticsAPI:Semantics\"]\n"
      "        )\n        {{\n"
      "            float3[] extent = [({}, {}, {}), ({}, {}, {})]\n"
      "            int[] faceVertexCounts = [{}]\n"
      "            int[] faceVertexIndices = [{}]\n"
      "            point3f[] points = [{}]\n",
      name, Num(box.min().x()), Num(box.min().y()), Num(box.min().z()),
      Num(box.max().x()), Num(box.max().y()), Num(box.max().z()), counts,
      indices, points);
  if (!m.normals.empty()) {
    text += fmt::format(
        "            normal3f[] normals = [{}] (\n                "
        "interpolation = \"vertex\"\n"
        "            )\n",
        normals);
  }
  if (!m.vertex_colors.empty()) {
    text += fmt::format(
        "            color3f[] primvars:displayColor = [{}] (\n"
        "                interpolation = \"vertex\"\n            )\n",
        colors);
  } else {
    text += fmt::format(
        "            color3f[] primvars:displayColor = [{}] (\n"
        "                interpolation = \"constant\"\n            )\n",
        Color3(m.color));
  }
  text += fmt::format(
      "            uniform token subdivisionScheme = \"none\"\n"
      "{}"
      "            custom int semrec:instanceId = {}\n"
      "            custom token semrec:kind = \"{}\"\n"
      "            custom string semrec:label = {}\n"
      "            custom int semrec:pointCount = {}\n"
      "            custom int semrec:firstSeenFrame = {}\n"
      "            custom int semrec:lastSeenFrame = {}\n"
      "            custom float semrec:confidence = {}\n"
      "{}"
      "        }}\n",
      detail::SemanticsAttributes(m.label, "            "), m.instance_id,
      m.structure ? "stuff" : "thing", label, m.point_count, m.first_seen_frame,
      m.last_seen_frame, Num(static_cast<float>(m.confidence)),
      m.class_votes.empty()
          ? std::string()
          : fmt::format("            custom string semrec:classVotes = {}\n",
                        Quote(m.class_votes)));
  return text;
}

std::string ObjectsScopeText(const std::vector<MeshPrim>& meshes) {
  // Objects by class and instance; structure (walls, floor...) one prim per
  // class, named by the class alone: /World/Structure/wall.
  std::string objects, structure;
  std::set<std::string> names;
  for (const MeshPrim& m : meshes) {
    const std::string name =
        m.structure
            ? SanitizeName(m.label)
            : fmt::format("{}_{}", SanitizeName(m.label), m.instance_id);
    CheckArgument(names.insert((m.structure ? "S/" : "O/") + name).second,
                  std::string("usd: duplicate ") +
                      (m.structure ? "structure" : "object") + " prim " + name);
    (m.structure ? structure : objects) += MeshPrimText(m, name);
  }
  std::string text = "    def Scope \"Objects\"\n    {\n" + objects + "    }\n";
  if (!structure.empty()) {
    text += "    def Scope \"Structure\"\n    {\n" + structure + "    }\n";
  }
  return text;
}

}  // namespace detail

std::string StaticLayerText(const std::vector<MeshPrim>& meshes,
                            const StageOptions& options) {
  options.Check();
  return Header(options, "") + "def Xform \"World\"\n{\n" +
         detail::ObjectsScopeText(meshes) + "}\n";
}

std::string FlatLayerText(const std::vector<MeshPrim>& meshes,
                          const std::vector<PersonTrack>& people,
                          const StageOptions& options) {
  options.Check();
  return Header(options, "") + "def Xform \"World\"\n{\n" +
         detail::ObjectsScopeText(meshes) +
         detail::PeopleScopeText(people, options) + "}\n";
}

std::string RootLayerText(const std::vector<std::string>& sublayers,
                          const StageOptions& options) {
  options.Check();
  std::string list;
  for (size_t i = 0; i < sublayers.size(); ++i) {
    list += fmt::format("{}        @{}@", i ? ",\n" : "", sublayers[i]);
  }
  return Header(options, "    subLayers = [\n" + list + "\n    ]\n") +
         "def Xform \"World\"\n{\n}\n";
}

void WriteScene(const std::filesystem::path& dir,
                const std::vector<MeshPrim>& meshes,
                const StageOptions& options,
                const std::vector<PersonTrack>& people) {
  // Both texts first: bad input throws before anything is written.
  const std::string static_text = StaticLayerText(meshes, options);
  const std::string dynamic_text = DynamicLayerText(people, options);
  WriteTextFileAtomic(dir / "static.usda", static_text);
  WriteTextFileAtomic(dir / "dynamic.usda", dynamic_text);
  // The stronger layer first; people and objects never share prims anyway.
  WriteTextFileAtomic(
      dir / "scene.usda",
      RootLayerText({"./dynamic.usda", "./static.usda"}, options));
}

void WriteSceneUsdz(const std::filesystem::path& path,
                    const std::vector<MeshPrim>& meshes,
                    const StageOptions& options,
                    const std::vector<PersonTrack>& people) {
  WriteUsdz(path, {{"scene.usda", FlatLayerText(meshes, people, options)}});
}

}  // namespace semrec::usd
