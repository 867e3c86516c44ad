#include "semrec/usd/glb_writer.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>

#include <fmt/format.h>
#include <tiny_gltf.h>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"

namespace semrec::usd {
namespace {

using tinygltf::Value;

constexpr int kFloat = TINYGLTF_COMPONENT_TYPE_FLOAT;
constexpr int kUint = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;

// Appends buffer views and accessors to one binary buffer (the GLB's BIN
// chunk).
class Builder {
 public:
  Builder() {
    model_.asset.version = "2.0";
    model_.asset.generator = "semrec";
    model_.buffers.emplace_back();
  }
  tinygltf::Model& model() { return model_; }

  int View(const void* data, size_t bytes, int target) {
    auto& bin = model_.buffers[0].data;
    bin.resize((bin.size() + 3) / 4 * 4, 0);  // accessors need 4-byte alignment
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = bin.size();
    view.byteLength = bytes;
    view.target = target;
    const auto* begin = static_cast<const unsigned char*>(data);
    bin.insert(bin.end(), begin, begin + bytes);
    model_.bufferViews.push_back(view);
    return static_cast<int>(model_.bufferViews.size()) - 1;
  }

  // Float VEC3 accessor (with the min/max glTF requires for positions).
  int Vec3(const std::vector<Eigen::Vector3f>& values,
           int target = TINYGLTF_TARGET_ARRAY_BUFFER) {
    std::vector<float> flat;
    flat.reserve(values.size() * 3);
    Eigen::Vector3f lo =
        Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
    Eigen::Vector3f hi = -lo;
    for (const auto& v : values) {
      flat.insert(flat.end(), {v.x(), v.y(), v.z()});
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    tinygltf::Accessor a;
    a.bufferView = View(flat.data(), flat.size() * sizeof(float), target);
    a.componentType = kFloat;
    a.count = values.size();
    a.type = TINYGLTF_TYPE_VEC3;
    if (!values.empty()) {
      a.minValues = {lo.x(), lo.y(), lo.z()};
      a.maxValues = {hi.x(), hi.y(), hi.z()};
    }
    return Push(a);
  }

  int Scalars(const std::vector<float>& values) {
    tinygltf::Accessor a;
    a.bufferView = View(values.data(), values.size() * sizeof(float), 0);
    a.componentType = kFloat;
    a.count = values.size();
    a.type = TINYGLTF_TYPE_SCALAR;
    if (!values.empty()) {
      a.minValues = {*std::min_element(values.begin(), values.end())};
      a.maxValues = {*std::max_element(values.begin(), values.end())};
    }
    return Push(a);
  }

  int Indices(const std::vector<std::array<uint32_t, 3>>& triangles) {
    std::vector<uint32_t> flat;
    flat.reserve(triangles.size() * 3);
    for (const auto& t : triangles) flat.insert(flat.end(), t.begin(), t.end());
    tinygltf::Accessor a;
    a.bufferView = View(flat.data(), flat.size() * sizeof(uint32_t),
                        TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    a.componentType = kUint;
    a.count = flat.size();
    a.type = TINYGLTF_TYPE_SCALAR;
    return Push(a);
  }

  int Material(const std::string& name, const std::array<double, 4>& color) {
    const std::string key =
        fmt::format("{}/{}/{}/{}", color[0], color[1], color[2], color[3]);
    if (const auto it = materials_.find(key); it != materials_.end()) {
      return it->second;
    }
    tinygltf::Material m;
    m.name = name;
    m.pbrMetallicRoughness.baseColorFactor = {color[0], color[1], color[2],
                                              color[3]};
    m.pbrMetallicRoughness.metallicFactor = 0.0;
    m.pbrMetallicRoughness.roughnessFactor = 0.9;
    m.doubleSided = true;  // fused surfaces are seen from both sides
    model_.materials.push_back(m);
    return materials_[key] = static_cast<int>(model_.materials.size()) - 1;
  }

  int Node(tinygltf::Node node) {
    model_.nodes.push_back(std::move(node));
    return static_cast<int>(model_.nodes.size()) - 1;
  }

 private:
  int Push(const tinygltf::Accessor& a) {
    model_.accessors.push_back(a);
    return static_cast<int>(model_.accessors.size()) - 1;
  }
  tinygltf::Model model_;
  std::map<std::string, int> materials_;
};

std::array<double, 4> Rgba(const std::array<uint8_t, 3>& c) {
  return {c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, 1.0};
}

void CheckMesh(const MeshPrim& m, const std::string& name) {
  const size_t n = m.points.size();
  CheckArgument(m.normals.empty() || m.normals.size() == n,
                name + ": normals must be empty or one per vertex");
  CheckArgument(m.vertex_colors.empty() || m.vertex_colors.size() == n,
                name + ": vertex colours must be empty or one per vertex");
  for (const auto& t : m.triangles) {
    CheckArgument(t[0] < n && t[1] < n && t[2] < n,
                  name + ": a triangle index is out of range");
  }
}

int MeshNode(Builder* b, const MeshPrim& m) {
  const std::string name =
      m.structure ? SanitizeName(m.label)
                  : fmt::format("{}_{}", SanitizeName(m.label), m.instance_id);
  CheckMesh(m, name);
  tinygltf::Primitive prim;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  prim.attributes["POSITION"] = b->Vec3(m.points);
  if (!m.normals.empty()) prim.attributes["NORMAL"] = b->Vec3(m.normals);
  if (!m.vertex_colors.empty()) {
    std::vector<Eigen::Vector3f> colors;
    colors.reserve(m.vertex_colors.size());
    for (const auto& c : m.vertex_colors) {
      colors.emplace_back(c[0] / 255.f, c[1] / 255.f, c[2] / 255.f);
    }
    prim.attributes["COLOR_0"] = b->Vec3(colors);
    prim.material = b->Material("vertex_color", {1.0, 1.0, 1.0, 1.0});
  } else {
    prim.material = b->Material(name, Rgba(m.color));
  }
  if (!m.triangles.empty()) prim.indices = b->Indices(m.triangles);
  tinygltf::Mesh mesh;
  mesh.name = name;
  mesh.primitives.push_back(prim);
  b->model().meshes.push_back(mesh);

  tinygltf::Node node;
  node.name = name;
  node.mesh = static_cast<int>(b->model().meshes.size()) - 1;
  node.extras = Value(Value::Object{
      {"semrec_class", Value(m.label)},
      {"semrec_instance_id", Value(static_cast<int>(m.instance_id))},
      {"semrec_kind", Value(std::string(m.structure ? "structure" : "thing"))},
      {"semrec_point_count",
       Value(static_cast<int>(std::min<size_t>(m.point_count, INT32_MAX)))},
      {"semrec_first_seen_frame", Value(static_cast<int>(m.first_seen_frame))},
      {"semrec_last_seen_frame", Value(static_cast<int>(m.last_seen_frame))},
      {"semrec_confidence", Value(m.confidence)},
  });
  return b->Node(node);
}

// A person: a point cloud (their first observation with points, relative to the
// centroid) whose node follows the centroid, scaled to 0 in the frames they are
// out of view.
int PersonNode(Builder* b, const PersonTrack& person,
               const StageOptions& options, tinygltf::Animation* animation) {
  const std::string name =
      fmt::format("{}_{}", SanitizeName(person.label), person.track_id);
  CheckArgument(!person.samples.empty(),
                name + ": a person needs at least one observation");
  tinygltf::Node node;
  node.name = name;
  node.extras = Value(Value::Object{
      {"semrec_class", Value(person.label)},
      {"semrec_instance_id", Value(static_cast<int>(person.track_id))},
      {"semrec_kind", Value(std::string("person"))},
      {"semrec_observations", Value(static_cast<int>(person.samples.size()))},
  });
  // glTF cannot change a cloud over time without morph targets of equal size:
  // the person's fullest view stands for them (their first may show only an arm
  // entering the picture).
  const auto with_points =
      std::max_element(person.samples.begin(), person.samples.end(),
                       [](const PersonSample& a, const PersonSample& b) {
                         return a.points_world.size() < b.points_world.size();
                       });
  if (!with_points->points_world.empty()) {
    std::vector<Eigen::Vector3f> local;
    local.reserve(with_points->points_world.size());
    for (const auto& p : with_points->points_world) {
      local.push_back(p - with_points->centroid_world);
    }
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_POINTS;
    prim.attributes["POSITION"] = b->Vec3(local);
    prim.material = b->Material(name, Rgba(person.color));
    tinygltf::Mesh mesh;
    mesh.name = name;
    mesh.primitives.push_back(prim);
    b->model().meshes.push_back(mesh);
    node.mesh = static_cast<int>(b->model().meshes.size()) - 1;
  }
  const Eigen::Vector3f first = person.samples.front().centroid_world;
  node.translation = {first.x(), first.y(), first.z()};
  const int index = b->Node(node);

  if (options.time_codes_per_second > 0) {
    std::map<size_t, const PersonSample*> by_frame;
    for (const PersonSample& s : person.samples) by_frame[s.frame] = &s;
    const auto begin =
        static_cast<size_t>(std::max(0.0, options.start_time_code));
    const auto end = std::max(
        begin, static_cast<size_t>(std::max(0.0, options.end_time_code)));
    std::vector<float> times;
    std::vector<Eigen::Vector3f> translation, scale;
    Eigen::Vector3f at = first;
    for (size_t f = begin; f <= end; ++f) {
      const auto it = by_frame.find(f);
      if (it != by_frame.end()) at = it->second->centroid_world;
      times.push_back(
          static_cast<float>((f - begin) / options.time_codes_per_second));
      translation.push_back(at);
      scale.push_back(
          Eigen::Vector3f::Constant(it != by_frame.end() ? 1.f : 0.f));
    }
    const int input = b->Scalars(times);
    for (const auto& [path, values] :
         {std::pair{"translation", &translation}, std::pair{"scale", &scale}}) {
      tinygltf::AnimationSampler sampler;
      sampler.input = input;
      sampler.output = b->Vec3(*values, 0);
      sampler.interpolation = "STEP";
      animation->samplers.push_back(sampler);
      tinygltf::AnimationChannel channel;
      channel.sampler = static_cast<int>(animation->samplers.size()) - 1;
      channel.target_node = index;
      channel.target_path = path;
      animation->channels.push_back(channel);
    }
  }
  return index;
}

tinygltf::Node Group(const std::string& name, std::vector<int> children) {
  tinygltf::Node node;
  node.name = name;
  node.children = std::move(children);
  return node;
}

}  // namespace

std::string GlbBytes(const std::vector<MeshPrim>& meshes,
                     const StageOptions& options,
                     const std::vector<PersonTrack>& people) {
  options.Check();
  Builder b;
  std::vector<int> objects, structure, persons;
  for (const MeshPrim& m : meshes) {
    (m.structure ? structure : objects).push_back(MeshNode(&b, m));
  }
  tinygltf::Animation animation;
  animation.name = "people";
  for (const PersonTrack& p : people) {
    persons.push_back(PersonNode(&b, p, options, &animation));
  }
  if (!animation.channels.empty()) b.model().animations.push_back(animation);

  std::vector<int> groups;
  if (!objects.empty()) groups.push_back(b.Node(Group("Objects", objects)));
  if (!structure.empty()) {
    groups.push_back(b.Node(Group("Structure", structure)));
  }
  if (!persons.empty()) groups.push_back(b.Node(Group("People", persons)));
  tinygltf::Node world = Group("World", groups);
  if (options.up_axis == "Z") {
    // glTF is Y-up: -90 degrees about X maps (x, y, z) to (x, z, -y).
    world.rotation = {-0.7071067811865476, 0.0, 0.0, 0.7071067811865476};
  }
  if (options.meters_per_unit != 1.0) {
    world.scale = {options.meters_per_unit, options.meters_per_unit,
                   options.meters_per_unit};
  }
  world.extras = Value(Value::Object{
      {"semrec_up_axis", Value(options.up_axis)},
      {"semrec_meters_per_unit", Value(options.meters_per_unit)}});
  const int root = b.Node(world);
  tinygltf::Scene scene;
  scene.name = "semrec";
  scene.nodes = {root};
  b.model().scenes.push_back(scene);
  b.model().defaultScene = 0;
  b.model().buffers[0].data.resize(
      (b.model().buffers[0].data.size() + 3) / 4 * 4, 0);

  tinygltf::TinyGLTF gltf;
  std::ostringstream out;
  if (!gltf.WriteGltfSceneToStream(&b.model(), out, /*prettyPrint=*/false,
                                   /*writeBinary=*/true)) {
    throw Error("GLB export failed (tinygltf could not serialise the scene)");
  }
  return out.str();
}

void WriteSceneGlb(const std::filesystem::path& path,
                   const std::vector<MeshPrim>& meshes,
                   const StageOptions& options,
                   const std::vector<PersonTrack>& people) {
  WriteTextFileAtomic(path, GlbBytes(meshes, options, people));  // binary-safe
}

}  // namespace semrec::usd
