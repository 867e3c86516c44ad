// semrec's Python module (`import semrec`; this is its native part,
// semrec._semrec): sequences in, the streaming pipeline, whole runs. Heavy
// calls release the GIL. Errors: semrec.FormatError / semrec.IoError (both
// OSError, naming the file), ValueError for bad options and arguments,
// TypeError for arrays of the wrong dtype.
#include <memory>
#include <optional>
#include <string>

#include <nanobind/nanobind.h>
#include <nanobind/stl/function.h>
#include <nanobind/stl/map.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "arrays.h"
#include "semrec/core/error.h"
#include "semrec/core/logging.h"
#include "semrec/infer/model_registry.h"
#include "semrec/io/label_set_io.h"
#include "semrec/io/sequence_reader.h"
#include "semrec/pipeline/people_3d.h"
#include "semrec/pipeline/run_sequence.h"
#include "semrec/pipeline/scene_pipeline.h"
#include "semrec/tasks/run_task.h"

namespace semrec::python {
namespace {

nb::dict IntrinsicsDict(const CameraIntrinsics& k) {
  nb::dict d;
  d["width"] = k.width;
  d["height"] = k.height;
  d["fx"] = k.fx;
  d["fy"] = k.fy;
  d["cx"] = k.cx;
  d["cy"] = k.cy;
  d["K"] = MatrixToArray(k.K());
  return d;
}

// One frame of a sequence, as numpy arrays (each made once, without copying
// the decoded image).
struct PyFrame {
  size_t index = 0;
  double timestamp = 0.0;
  nb::object color, depth, T_world_camera, K;
  nb::object semantic = nb::none(), instance = nb::none(), person = nb::none();
  std::string color_path;
};

class PySequence {
 public:
  PySequence(const std::string& path, int stride, size_t max_frames,
             double max_depth_m, const std::optional<std::string>& labels) {
    io::SequenceReaderOptions o;
    o.stride = stride;
    o.max_frames = max_frames;
    o.max_depth_m = max_depth_m;
    // A recording without poses opens (has_poses False): run estimates them.
    o.require_poses = false;
    o.Check();
    reader_ =
        std::make_unique<io::SequenceReader>(io::SequenceReader::Open(path, o));
    if (labels) {
      source_ = fuse::SegmentationSource::Create(*labels, *reader_);
      if (*labels == "gt" &&
          reader_->index().frames.front().layers.contains("person")) {
        people_.emplace("gt", *reader_);
      }
    }
  }

  size_t size() const { return reader_->size(); }

  PyFrame Get(int64_t i) const {
    const int64_t n = static_cast<int64_t>(size());
    if (i < 0) i += n;
    if (i < 0 || i >= n) throw nb::index_error("frame index out of range");
    const size_t at = static_cast<size_t>(i);
    Frame f;
    std::optional<fuse::FrameLabels> labels;
    std::optional<LabelMap> person;
    {
      nb::gil_scoped_release release;
      f = reader_->Read(at);
      if (source_) labels = source_->Get(*reader_, at);
      if (people_) person = people_->Get(at);
    }
    PyFrame out;
    out.index = f.index;
    out.timestamp = f.timestamp_s;
    out.color_path = f.color_path.string();
    out.K = nb::cast(MatrixToArray(f.intrinsics.K()));
    out.T_world_camera = nb::cast(MatrixToArray(f.T_world_camera.Matrix()));
    out.color = nb::cast(ToArray(std::move(f.color)));
    out.depth = nb::cast(ToArray(std::move(f.depth)));
    if (labels) {
      out.semantic = nb::cast(ToArray(std::move(labels->semantic)));
      out.instance = nb::cast(ToArray(std::move(labels->instance)));
    }
    if (person) out.person = nb::cast(ToArray(std::move(*person)));
    return out;
  }

  std::string layout() const { return reader_->layout(); }
  bool has_poses() const { return reader_->index().has_poses; }
  std::string root() const { return reader_->root().string(); }
  nb::dict intrinsics() const { return IntrinsicsDict(reader_->intrinsics()); }
  // The label set of the given labels (None without labels).
  nb::object classes() const {
    if (!source_) return nb::none();
    nb::list out;
    for (const LabelClass& c : source_->classes().Classes()) {
      nb::dict d;
      d["id"] = c.id;
      d["name"] = c.name;
      d["kind"] = ClassKindName(c.kind);
      out.append(d);
    }
    return out;
  }
  std::optional<std::string> classes_name() const {
    if (!source_) return std::nullopt;
    return source_->classes().name();
  }

 private:
  std::unique_ptr<io::SequenceReader> reader_;
  std::unique_ptr<fuse::SegmentationSource> source_;
  std::optional<pipeline::PersonMapSource> people_;
};

// Iteration over a sequence's frames (each read when reached).
struct PySequenceIterator {
  const PySequence* sequence;
  nb::object keep_alive;
  size_t next = 0;
};

class PyPipeline {
 public:
  PyPipeline(const std::optional<std::string>& models,
             const std::optional<std::string>& classes, int segment_every,
             bool track_people, bool map_guidance, const std::string& merge,
             double alpha, double tsdf_voxel_m, double tsdf_trunc_m,
             double max_depth_m) {
    pipeline::ScenePipelineOptions o;
    o.segment_every = segment_every;
    o.track_people = track_people;
    o.map_guidance = map_guidance;
    o.scene.fusion.merge = fuse::ParseMerge(merge);
    o.scene.fusion.alpha = alpha;
    o.scene.meshing.tsdf.voxel_size_m = tsdf_voxel_m;
    o.scene.meshing.tsdf.sdf_trunc_m = tsdf_trunc_m;
    o.scene.meshing.tsdf.max_depth_m = max_depth_m;
    o.overlays = false;
    if (models) {
      tasks::ModelChoice choice;  // the models `semrec run` uses
      if (*models != "default") choice.registry = *models;
      registry_ = std::make_unique<infer::ModelRegistry>(
          infer::ModelRegistry::LoadDefaultWith(choice.registry));
      tasks::ApplyModelChoice(*registry_, choice, &o);
    } else {
      Require(classes.has_value(), false,
              "Pipeline: without models every frame brings its labels; say "
              "which label set they use (classes='ade20k', a classes.json "
              "path, or Sequence.classes_name)");
      o.labels = pipeline::ScenePipelineOptions::Labels::kGiven;
      classes_ = io::LoadLabelSet(*classes);
    }
    o.Check();
    given_ = !models.has_value();
    pipeline_ = std::make_unique<pipeline::ScenePipeline>(
        registry_.get(), given_ ? &classes_ : nullptr, o);
  }

  nb::dict AddFrame(
      const AnyArray& color, const AnyArray& depth, const AnyArray& K,
      const AnyArray& T_world_camera, std::optional<double> timestamp,
      std::optional<AnyArray> semantic, std::optional<AnyArray> instance,
      const std::optional<AnyArray>& person, double depth_scale,
      const std::optional<std::pair<AnyArray, AnyArray>>& labels) {
    Require(!finished_, false, "Pipeline: add_frame() after finish()");
    if (labels) {
      Require(!semantic && !instance, false,
              "add_frame: give labels=(semantic, instance) or semantic= and "
              "instance=, not both");
      semantic = labels->first;
      instance = labels->second;
    }
    pipeline::PipelineInput input;
    Frame& f = input.frame;
    f.index = frames_;
    f.timestamp_s = timestamp.value_or(static_cast<double>(frames_));
    f.color = ToImage<uint8_t>(color, "color", 3);
    if (depth.dtype() == nb::dtype<uint16_t>()) {
      Require(depth_scale > 0.0, false, "depth_scale must be > 0");
      f.depth =
          DepthToMeters(ToImage<uint16_t>(depth, "depth", 1), depth_scale);
    } else {
      Require(depth.dtype() == nb::dtype<float>(), true,
              "depth: expected float32 (metres) or uint16 (raw, divided by "
              "depth_scale), got " +
                  DescribeDtype(depth));
      f.depth = ToImage<float>(depth, "depth", 1);
    }
    Require(f.depth.SameSize(f.color), false,
            "depth: its size differs from the colour image's");
    const Eigen::Matrix3d k = ToMatrix<3, 3>(K, "K");
    f.intrinsics.width = f.color.width();
    f.intrinsics.height = f.color.height();
    f.intrinsics.fx = k(0, 0);
    f.intrinsics.fy = k(1, 1);
    f.intrinsics.cx = k(0, 2);
    f.intrinsics.cy = k(1, 2);
    f.intrinsics.Check();
    f.T_world_camera = Transform::FromMatrix(
        ToMatrix<4, 4>(T_world_camera, "T_world_camera"), "T_world_camera");
    input.name = "frame" + std::to_string(frames_) + ".png";
    if (given_) {
      Require(semantic.has_value() && instance.has_value(), false,
              "Pipeline without models: add_frame() needs semantic= and "
              "instance= (uint16 label maps)");
      LabelMap s = ToImage<uint16_t>(*semantic, "semantic", 1);
      LabelMap i = ToImage<uint16_t>(*instance, "instance", 1);
      Require(s.SameSize(f.color) && i.SameSize(f.color), false,
              "semantic/instance: their size differs from the colour image's");
      input.labels = fuse::FrameLabels(std::move(i), std::move(s), input.name);
      if (person) {
        LabelMap p = ToImage<uint16_t>(*person, "person", 1);
        Require(p.SameSize(f.color), false,
                "person: its size differs from the colour image's");
        input.person_ids = std::move(p);
      }
    } else {
      Require(!semantic && !instance && !person, false,
              "Pipeline with models: labels are not given (make a Pipeline "
              "with models=None to give them)");
    }
    pipeline::PipelineFrameResult r;
    {
      nb::gil_scoped_release release;
      r = pipeline_->Process(input);
    }
    ++frames_;
    nb::dict d;
    d["segmented"] = r.segmented;
    d["segments"] = r.segments;
    d["people"] = r.people;
    return d;
  }

  void Finish() {
    if (finished_) return;
    nb::gil_scoped_release release;
    pipeline_->Finish();
    finished_ = true;
  }

  nb::list Objects() const {
    const LabelSet& classes = pipeline_->classes();
    nb::list out;
    for (const fuse::SceneSegment& s : pipeline_->scene().fusion().segments()) {
      nb::dict d;
      d["id"] = s.id;
      d["class_id"] = s.class_id;
      d["class"] = classes.Contains(s.class_id) ? classes.Get(s.class_id).name
                                                : std::string("unknown");
      d["kind"] = ClassKindName(s.kind);
      nb::dict votes;
      for (const auto& [c, n] : s.class_votes) votes[nb::int_(c)] = n;
      d["class_votes"] = votes;
      d["frames_seen"] = s.frames_seen;
      d["points"] = PointsToArray(s.points);
      out.append(d);
    }
    return out;
  }

  nb::dict Meshes() {
    pipeline::SceneWriteResult r;
    std::vector<usd::MeshPrim> prims;
    {
      nb::gil_scoped_release release;
      prims = pipeline_->Meshes(&r);
    }
    nb::list objects;
    for (const usd::MeshPrim& p : prims) objects.append(MeshPrimDict(p));
    nb::dict out;
    out["objects"] = objects;
    out["T_upright_world"] = MatrixToArray(r.gravity.T_upright_world.Matrix());
    return out;
  }

  nb::list People() const {
    nb::list out;
    for (const io::MotBox& b : pipeline_->Tracks()) {
      nb::dict d;
      d["frame"] = b.frame - 1;
      d["id"] = b.id;
      d["box"] = nb::make_tuple(b.left, b.top, b.width, b.height);
      d["confidence"] = b.confidence;
      out.append(d);
    }
    return out;
  }

  nb::dict Write(const std::string& out_dir, bool ply, bool glb, bool usdz) {
    pipeline::SceneWriteOptions w;
    w.write_ply = ply;
    w.glb = glb;
    w.usdz = usdz;
    w.custom_layer_data["input"] = "python";
    pipeline::SceneWriteResult r;
    {
      nb::gil_scoped_release release;
      r = pipeline_->Write(out_dir, w);
    }
    nb::dict d;
    d["objects"] = r.objects;
    d["structure"] = r.structure;
    d["triangles"] = r.triangles;
    d["people"] = r.people;
    d["scene"] = (std::filesystem::path(out_dir) / "scene.usda").string();
    d["summary"] = FromJson(r.objects_json);
    // The scene is written upright (z up, floor at 0); objects() are in the
    // input's world frame: this maps one into the other.
    d["T_upright_world"] = MatrixToArray(r.gravity.T_upright_world.Matrix());
    return d;
  }

  nb::dict Report() const {
    const pipeline::StageSeconds& s = pipeline_->seconds();
    nb::dict seconds;
    seconds["segment"] = s.segment;
    seconds["track"] = s.track;
    seconds["fuse"] = s.fuse;
    seconds["volumes"] = s.volumes;
    seconds["write"] = s.write;
    nb::dict d;
    d["frames"] = pipeline_->frames();
    d["segmented_frames"] = pipeline_->segmented_frames();
    d["seconds"] = seconds;
    d["finished"] = finished_;
    return d;
  }

  size_t frames() const { return frames_; }

 private:
  std::unique_ptr<infer::ModelRegistry> registry_;
  LabelSet classes_;
  bool given_ = true;
  std::unique_ptr<pipeline::ScenePipeline> pipeline_;
  size_t frames_ = 0;
  bool finished_ = false;
};

nb::object Run(const std::string& sequence, const std::string& out,
               const std::optional<std::string>& labels,
               const std::optional<std::string>& models, int segment_every,
               bool map_guidance, bool overwrite, int stride, size_t max_frames,
               const std::optional<nb::callable>& on_progress, bool report,
               bool report_pictures, const std::string& poses) {
  // What `semrec run` does with the same arguments (tasks::RunTask).
  tasks::RunTaskOptions task;
  task.sequence = sequence;
  task.out = out;
  task.reader.stride = stride;
  task.reader.max_frames = max_frames;
  task.labels = fuse::LabelSpec::Parse(labels.value_or("models"));
  if (models && *models != "default") task.models.registry = *models;
  task.run.pipeline.segment_every = segment_every;
  task.run.pipeline.map_guidance = map_guidance;
  task.run.overwrite = overwrite;
  task.run.poses = pipeline::ParsePoses(poses);
  task.run.config_text = "python: semrec.run(" + sequence + ")";
  task.report_html = report;
  task.report_pictures = report_pictures;
  task.Check();
  tasks::RunTaskResult r;
  {
    nb::gil_scoped_release release;
    ProgressOptions progress;
    progress.mode = ProgressOptions::Mode::kOff;
    if (on_progress) {
      // On the run's main thread, which holds no GIL here; an exception the
      // callback raises stops the run and comes back to the caller.
      progress.on_tick = [&on_progress](size_t done, size_t total) {
        nb::gil_scoped_acquire gil;
        (*on_progress)(done, total);
      };
    }
    r = tasks::RunTask(task, progress);
  }
  return FromJson(pipeline::ToJson(r.run.report));
}

// semrec.Error, and file errors that are OSErrors too.
void BindErrors(nb::module_& m) {
  static nb::object error = nb::steal(
      PyErr_NewException("semrec.Error", PyExc_RuntimeError, nullptr));
  static nb::object io_error = nb::steal(PyErr_NewException(
      "semrec.IoError", nb::make_tuple(error, nb::handle(PyExc_OSError)).ptr(),
      nullptr));
  static nb::object format_error = nb::steal(PyErr_NewException(
      "semrec.FormatError",
      nb::make_tuple(error, nb::handle(PyExc_OSError)).ptr(), nullptr));
  m.attr("Error") = error;
  m.attr("IoError") = io_error;
  m.attr("FormatError") = format_error;
  nb::register_exception_translator([](const std::exception_ptr& p, void*) {
    try {
      std::rethrow_exception(p);
    } catch (const FormatError& e) {
      PyErr_SetString(format_error.ptr(), e.what());
    } catch (const IoError& e) {
      PyErr_SetString(io_error.ptr(), e.what());
    } catch (const InvalidArgument& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const Error& e) {
      PyErr_SetString(error.ptr(), e.what());
    }
  });
}

void BindSequence(nb::module_& m) {
  nb::class_<PyFrame>(m, "Frame",
                      "One RGB-D frame: numpy arrays (views of the decoded "
                      "images, no copies).")
      .def_ro("index", &PyFrame::index, "Position in the sequence.")
      .def_ro("timestamp", &PyFrame::timestamp, "Capture time (s).")
      .def_ro("color", &PyFrame::color, "H x W x 3 uint8 RGB.")
      .def_ro("depth", &PyFrame::depth, "H x W float32, metres (0 = none).")
      .def_ro("T_world_camera", &PyFrame::T_world_camera,
              "4 x 4 float64: camera to world.")
      .def_ro("K", &PyFrame::K, "3 x 3 float64 intrinsics.")
      .def_ro("semantic", &PyFrame::semantic,
              "H x W uint16 class ids (sequences opened with labels=), or "
              "None.")
      .def_ro("instance", &PyFrame::instance,
              "H x W uint16 instance ids (with labels=), or None.")
      .def_ro("person", &PyFrame::person,
              "H x W uint16 person ids (labels='gt' on sequences that have "
              "them), or None.")
      .def_ro("color_path", &PyFrame::color_path);

  nb::class_<PySequenceIterator>(m, "SequenceIterator")
      .def("__iter__", [](nb::handle self) { return nb::borrow(self); })
      .def("__next__", [](PySequenceIterator& it) {
        if (it.next >= it.sequence->size()) throw nb::stop_iteration();
        return it.sequence->Get(static_cast<int64_t>(it.next++));
      });

  nb::class_<PySequence>(m, "Sequence",
                         "An RGB-D sequence on disk (7-Scenes, TUM, Redwood, "
                         "semrec manifest), read frame by frame.")
      .def(nb::init<const std::string&, int, size_t, double,
                    const std::optional<std::string>&>(),
           nb::arg("path"), nb::arg("stride") = 1, nb::arg("max_frames") = 0,
           nb::arg("max_depth_m") = 0.0, nb::arg("labels").none() = nb::none())
      .def("__len__", &PySequence::size)
      .def("__getitem__", &PySequence::Get, nb::arg("i"))
      .def(
          "__iter__",
          [](nb::handle self) {
            return PySequenceIterator{nb::inst_ptr<PySequence>(self),
                                      nb::borrow(self), 0};
          },
          "The frames in order, each read when reached.")
      .def_prop_ro("layout", &PySequence::layout)
      .def_prop_ro("has_poses", &PySequence::has_poses,
                   "False for a recording without poses (every pose is the "
                   "identity; semrec.run(poses='auto') estimates them)")
      .def_prop_ro("root", &PySequence::root)
      .def_prop_ro("intrinsics", &PySequence::intrinsics)
      .def_prop_ro("classes", &PySequence::classes,
                   "The given labels' classes (list of dicts), or None.")
      .def_prop_ro("classes_name", &PySequence::classes_name);
}

void BindPipeline(nb::module_& m) {
  nb::class_<PyPipeline>(
      m, "Pipeline",
      "The streaming pipeline: add frames one by one, read the objects, write "
      "the USD scene. models='default' runs the segmentation models and the "
      "people tracker; models=None takes labels with every frame (classes= "
      "names their label set).")
      .def(nb::init<const std::optional<std::string>&,
                    const std::optional<std::string>&, int, bool, bool,
                    const std::string&, double, double, double, double>(),
           nb::arg("models").none() = "default",
           nb::arg("classes").none() = nb::none(), nb::arg("segment_every") = 1,
           nb::arg("track_people") = true, nb::arg("map_guidance") = false,
           nb::arg("merge") = "voxel", nb::arg("alpha") = 0.5,
           nb::arg("tsdf_voxel_m") = 0.02, nb::arg("tsdf_trunc_m") = 0.08,
           nb::arg("max_depth_m") = 4.0,
           "models: 'default', a registry YAML (merged over the installed "
           "one; the models are those of `semrec run`), or None (labels come "
           "with "
           "the frames; classes= names their label set). segment_every: "
           "segment every n-th frame (people every frame). merge: 'voxel' "
           "(objects decided per map voxel), 'evidence' or 'paper' (the "
           "overlap rule alone, merge when sigma > alpha). tsdf_*: each "
           "object's volume. Bad values raise ValueError.")
      .def("add_frame", &PyPipeline::AddFrame, nb::arg("color"),
           nb::arg("depth"), nb::arg("K"), nb::arg("T_world_camera"),
           nb::arg("timestamp").none() = nb::none(),
           nb::arg("semantic").none() = nb::none(),
           nb::arg("instance").none() = nb::none(),
           nb::arg("person").none() = nb::none(),
           nb::arg("depth_scale") = 1000.0,
           nb::arg("labels").none() = nb::none(),
           "Runs every stage on one frame. labels=(semantic, instance) (or "
           "semantic=, instance=): uint16 maps, for a Pipeline without models. "
           "color: H x W x 3 uint8; depth: H x "
           "W float32 metres or uint16 (divided by depth_scale); K 3 x 3; "
           "T_world_camera 4 x 4 (camera to world).")
      .def("finish", &PyPipeline::Finish,
           "Ends the stream (the objects are decided per map voxel).")
      .def("objects", &PyPipeline::Objects,
           "The objects (after finish(): the final ones): id, class, kind, "
           "class votes, frames seen, points (N x 3 float32, world frame).")
      .def("meshes", &PyPipeline::Meshes,
           "Each object's mesh as write() would write it, without files: "
           "dict(objects=[id, class, kind, vertices N x 3 float32, faces M x "
           "3 uint32, confidence], T_upright_world: input world -> the "
           "meshes' upright frame).")
      .def("people", &PyPipeline::People, "Tracked people boxes per frame.")
      .def("write", &PyPipeline::Write, nb::arg("out_dir"),
           nb::arg("ply") = true, nb::arg("glb") = false,
           nb::arg("usdz") = false,
           "Writes scene.usda (and PLY/GLB/USDZ) to out_dir.")
      .def("report", &PyPipeline::Report)
      .def_prop_ro("frames", &PyPipeline::frames);
}

}  // namespace

NB_MODULE(_semrec, m) {
  m.doc() = "semrec's native module; use `import semrec`.";
  BindErrors(m);
  BindSequence(m);
  BindPipeline(m);
  BindSegmenter(m);
  BindEval(m);
  BindLoad(m);

  m.def("set_log_level", &InitLogging, nb::arg("level") = "info",
        "semrec's messages on stderr: trace, debug, info (default), warn, "
        "error or off.");

  m.def("run", &Run, nb::arg("sequence"), nb::arg("out"),
        nb::arg("labels").none() = nb::none(),
        nb::arg("models").none() = nb::none(), nb::arg("segment_every") = 1,
        nb::arg("map_guidance") = false, nb::arg("overwrite") = false,
        nb::arg("stride") = 1, nb::arg("max_frames") = 0,
        nb::arg("progress").none() = nb::none(), nb::arg("report") = true,
        nb::arg("report_pictures") = false, nb::arg("poses") = "auto",
        "As `semrec run`: the whole sequence into out/; returns report.json "
        "as a dict. labels='gt' (or a label folder) skips the models. "
        "progress: called with (frames done, frames) after each frame (e.g. "
        "to update a tqdm bar); an exception it raises stops the run. "
        "report: write out/report.html as `semrec run` does; "
        "report_pictures: with pictures of the scene (the browser viewer in "
        "headless Chromium, a few seconds). poses: 'auto' (the recording's, "
        "estimated when it has none), 'estimate' or 'file', as --poses.");
}

}  // namespace semrec::python
