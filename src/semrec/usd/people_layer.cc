// dynamic.usda: tracked people as time-sampled prims.
#include <set>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "semrec/core/error.h"
#include "semrec/usd/usda_text.h"
#include "semrec/usd/usda_writer.h"

namespace semrec::usd {

using detail::Num;

namespace {

std::string Vec3(const Eigen::Vector3f& v) {
  return fmt::format("({}, {}, {})", Num(v.x()), Num(v.y()), Num(v.z()));
}

std::string PersonPrim(const std::string& name, const PersonTrack& person) {
  // Time samples: one per observation; visibility switches off on the first
  // frame without one and back on at the next observation. Before the first
  // and after the last observation the person is invisible too.
  std::string translate, visibility, points, extent;
  size_t previous = 0;
  for (size_t k = 0; k < person.samples.size(); ++k) {
    const PersonSample& s = person.samples[k];
    const bool first = k == 0;
    if (!first) {
      CheckArgument(s.frame > previous,
                    fmt::format("usd: person {} has samples out of frame order "
                                "({} after {})",
                                person.track_id, s.frame, previous));
    }
    if (first || s.frame > previous + 1) {
      if (!first) {
        visibility +=
            fmt::format("            {}: \"invisible\",\n", previous + 1);
      } else if (s.frame > 0) {
        visibility += "            0: \"invisible\",\n";
      }
      visibility += fmt::format("            {}: \"inherited\",\n", s.frame);
    }
    translate +=
        fmt::format("            {}: {},\n", s.frame, Vec3(s.centroid_world));
    Eigen::AlignedBox3f box;
    std::string cloud;
    for (size_t i = 0; i < s.points_world.size(); ++i) {
      const Eigen::Vector3f local = s.points_world[i] - s.centroid_world;
      box.extend(local);
      cloud += (i ? ", " : "") + Vec3(local);
    }
    if (s.points_world.empty()) box.extend(Eigen::Vector3f::Zero());
    points += fmt::format("                {}: [{}],\n", s.frame, cloud);
    extent += fmt::format("                {}: [{}, {}],\n", s.frame,
                          Vec3(box.min()), Vec3(box.max()));
    previous = s.frame;
  }
  if (!person.samples.empty()) {
    visibility += fmt::format("            {}: \"invisible\",\n", previous + 1);
  }
  const size_t first_frame =
      person.samples.empty() ? 0 : person.samples.front().frame;
  return fmt::format(
      "        def Xform \"{name}\" (\n"
      "            prepend apiSchemas = [\"SemanticsLabelsAPI:class\", "
      "\"SemanticsAPI:Semantics\"]\n"
      "        )\n        {{\n"
      "            token visibility.timeSamples = {{\n{visibility}"
      "            }}\n"
      "            double3 xformOp:translate.timeSamples = {{\n{translate}"
      "            }}\n"
      "            uniform token[] xformOpOrder = [\"xformOp:translate\"]\n"
      "{semantics}"
      "            custom int semrec:trackId = {id}\n"
      "            custom string semrec:label = {label}\n"
      "            custom int semrec:firstSeenFrame = {first}\n"
      "            custom int semrec:lastSeenFrame = {last}\n"
      "            custom int semrec:observations = {count}\n\n"
      "            def Points \"Cloud\"\n            {{\n"
      "                float3[] extent.timeSamples = {{\n{extent}"
      "                }}\n"
      "                point3f[] points.timeSamples = {{\n{points}"
      "                }}\n"
      "                color3f[] primvars:displayColor = [{color}] (\n"
      "                    interpolation = \"constant\"\n"
      "                )\n"
      "                float[] widths = [0.05] (\n"
      "                    interpolation = \"constant\"\n"
      "                )\n"
      "            }}\n"
      "        }}\n",
      fmt::arg("name", name), fmt::arg("visibility", visibility),
      fmt::arg("translate", translate),
      fmt::arg("semantics",
               detail::SemanticsAttributes(person.label, "            ")),
      fmt::arg("id", person.track_id),
      fmt::arg("label", detail::Quote(person.label)),
      fmt::arg("first", first_frame), fmt::arg("last", previous),
      fmt::arg("count", person.samples.size()), fmt::arg("extent", extent),
      fmt::arg("points", points),
      fmt::arg("color", detail::Color3(person.color)));
}

}  // namespace

namespace detail {

std::string PeopleScopeText(const std::vector<PersonTrack>& people,
                            const StageOptions& options) {
  CheckArgument(people.empty() || options.time_codes_per_second > 0.0,
                "usd: people need time_codes_per_second > 0 (the frame rate)");
  std::string text = "    def Scope \"People\"\n    {\n";
  std::set<std::string> names;
  for (const PersonTrack& person : people) {
    const std::string name =
        fmt::format("{}_{}", SanitizeName(person.label), person.track_id);
    CheckArgument(names.insert(name).second,
                  "usd: duplicate person prim " + name);
    CheckArgument(
        !person.samples.empty(),
        fmt::format("usd: person {} has no observations", person.track_id));
    text += PersonPrim(name, person);
  }
  text += "    }\n";
  return text;
}

}  // namespace detail

std::string DynamicLayerText(const std::vector<PersonTrack>& people,
                             const StageOptions& options) {
  options.Check();
  return detail::Header(options, "") + "def Xform \"World\"\n{\n" +
         detail::PeopleScopeText(people, options) + "}\n";
}

}  // namespace semrec::usd
