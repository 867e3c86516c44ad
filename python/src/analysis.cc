// The module's single-image segmenter (semrec.Segmenter), evaluations
// (semrec.eval) and written results read back (semrec.load): thin wrappers
// over the library's calls.
#include <memory>
#include <optional>
#include <string>

#include <nanobind/nanobind.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>

#include "arrays.h"
#include "semrec/eval/scene_result.h"
#include "semrec/infer/model_registry.h"
#include "semrec/io/label_set_io.h"
#include "semrec/segment/hybrid_segmenter.h"
#include "semrec/usd/usda_reader.h"

namespace semrec::python {
namespace {

// The hybrid segmenter on single images (models loaded once, kept).
class PySegmenter {
 public:
  PySegmenter(const std::string& models, bool use_masks,
              const std::optional<std::string>& object_detector) {
    registry_ = LoadRegistry(models);
    segment::HybridSegmenterOptions o;
    o.use_masks = use_masks;
    if (use_masks && object_detector) o.objects.model = *object_detector;
    o.Check();
    segmenter_ = std::make_unique<segment::HybridSegmenter>(*registry_, o);
  }

  nb::dict Segment(const AnyArray& image) {
    const ColorImage rgb = ToImage<uint8_t>(image, "image", 3);
    segment::HybridResult r;
    {
      nb::gil_scoped_release release;
      r = segmenter_->Segment(rgb);
    }
    nb::dict d;
    d["semantic"] = ToArray(std::move(r.vote.semantic));
    d["instance"] = ToArray(std::move(r.vote.instance));
    nb::dict classes;
    for (const LabelClass& c : segmenter_->label_set().Classes()) {
      classes[nb::int_(c.id)] = c.name;
    }
    d["classes"] = classes;
    d["masks"] = r.masks.size();
    return d;
  }

 private:
  std::unique_ptr<infer::ModelRegistry> registry_;
  std::unique_ptr<segment::HybridSegmenter> segmenter_;
};

}  // namespace

void BindSegmenter(nb::module_& m) {
  nb::class_<PySegmenter>(
      m, "Segmenter",
      "Hybrid semantic segmentation of single images (as `semrec segment`): "
      "the semantic model labels every pixel, SAM-style masks vote, object "
      "detections add evidence. Models load once.")
      .def(nb::init<const std::string&, bool,
                    const std::optional<std::string>&>(),
           nb::arg("models") = "default", nb::arg("masks") = true,
           nb::arg("object_detector").none() = DefaultDetector())
      .def("__call__", &PySegmenter::Segment, nb::arg("image"),
           "image: H x W x 3 uint8 RGB -> dict(semantic=H x W uint16, "
           "instance=H x W uint16, classes={id: name}, masks=count).");
}

void BindEval(nb::module_& m) {
  nb::module_ ev = m.def_submodule(
      "eval", "Evaluation against ground truth, as `semrec eval ... --json`.");
  ev.def(
      "scene",
      [](const std::string& result, const std::string& gt,
         const std::optional<std::string>& gt_classes,
         const std::optional<std::string>& class_map,
         const std::optional<std::string>& observed_in, int observed_stride,
         double radius_m) {
        eval::SceneResultOptions o;
        o.result = result;
        o.gt = gt;
        if (gt_classes) o.gt_classes = *gt_classes;
        if (class_map) o.class_map = *class_map;
        if (observed_in) o.observed_in = *observed_in;
        o.observed_stride = observed_stride;
        o.metrics.radius_m = radius_m;
        nlohmann::json j;
        {
          nb::gil_scoped_release release;
          j = eval::EvaluateSceneResult(o).ToJson();
        }
        return FromJson(j);
      },
      nb::arg("result"), nb::arg("gt"),
      nb::arg("gt_classes").none() = nb::none(),
      nb::arg("class_map").none() = nb::none(),
      nb::arg("observed_in").none() = nb::none(),
      nb::arg("observed_stride") = 1, nb::arg("radius_m") = 0.05,
      "3D semantic and instance quality of a result folder (or scene.usda) "
      "against a ground-truth PLY: mean_iou, ap25, ap50, per class and per "
      "ground-truth object.");
  ev.def(
      "mot",
      [](const std::string& gt, const std::string& result) {
        return FromJson(
            eval::MotMetricsJson(eval::EvaluateMotFiles(gt, result)));
      },
      nb::arg("gt"), nb::arg("result"),
      "MOTChallenge metrics (MOTA, IDF1, HOTA, ...) of a tracker's output "
      "file against gt.txt.");
  ev.def(
      "seg",
      [](const std::string& pred, const std::string& gt,
         const std::string& labels, int boundary_tolerance_px) {
        eval::SegEvalOptions o;
        o.boundary_tolerance_px = boundary_tolerance_px;
        const LabelSet set = io::LoadLabelSet(labels);
        eval::SegMetrics m;
        {
          nb::gil_scoped_release release;
          m = eval::EvaluateSegFolders(pred, gt, set, o);
        }
        return FromJson(eval::SegMetricsJson(m, set));
      },
      nb::arg("pred"), nb::arg("gt"), nb::arg("labels") = "ade20k",
      nb::arg("boundary_tolerance_px") = 2,
      "Semantic segmentation metrics (pAcc, mIoU, boundary IoU/F) of label "
      "PNGs (or a `semrec segment` folder) against ground-truth PNGs.");
}

void BindLoad(nb::module_& m) {
  m.def(
      "load",
      [](const std::string& result) {
        namespace fs = std::filesystem;
        const fs::path scene = fs::is_directory(result)
                                   ? fs::path(result) / "scene.usda"
                                   : fs::path(result);
        std::vector<usd::MeshPrim> meshes;
        Transform T_upright_world;
        {
          nb::gil_scoped_release release;
          T_upright_world = eval::ResultUprightTransform(scene);
          meshes = usd::ReadScene(scene);
        }
        nb::list objects;
        for (const usd::MeshPrim& p : meshes) {
          objects.append(MeshPrimDict(p));
        }
        nb::dict out;
        out["scene"] = scene.string();
        out["objects"] = objects;
        out["T_upright_world"] = MatrixToArray(T_upright_world.Matrix());
        return out;
      },
      nb::arg("result"),
      "Reads a written result (a `semrec run` / `semrec mesh` folder, or its "
      "scene.usda) back: objects with id, class, kind, vertices (N x 3 "
      "float32, the scene's upright frame), faces (M x 3 uint32), fused "
      "points, confidence; and T_upright_world (input world -> scene).");
}

}  // namespace semrec::python
