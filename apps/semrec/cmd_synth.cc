// `semrec synth --preset NAME --out DIR`: synthetic RGB-D sequences with full
// ground truth.
#include <cstdio>
#include <optional>

#include <fmt/format.h>

#include "commands.h"
#include "semrec/core/error.h"
#include "semrec/synth/generator.h"

namespace semrec::cli {
namespace {

struct SynthArgs {
  std::string preset = "six-objects";
  std::string out;
  std::optional<int> frames;
  std::string views = "video";
  uint64_t seed = 1;
  std::string noise = "kinect";
  double noise_strength = 1.0;
  double max_depth_m = 4.0;
  std::optional<int> width;
  std::optional<int> height;
  std::optional<double> gt_spacing_m;
  bool label_noise = false;
  synth::LabelNoiseOptions label_noise_options;
  bool overwrite = false;
};

void RunSynth(const SynthArgs& args) {
  synth::SynthOptions options;
  try {
    options = synth::SynthOptions::Preset(args.preset);
  } catch (const InvalidArgument& e) {
    throw UsageError(e.what());
  }
  options.frames = args.frames.value_or(options.frames);
  CheckUsage(args.views == "video" || args.views == "sparse",
             "--views must be 'video' or 'sparse', got '" + args.views + "'");
  if (args.views == "sparse") {
    options.trajectory.kind = synth::TrajectoryOptions::Kind::kSparse;
  }
  // A different resolution keeps the field of view: the focal length scales
  // with the width.
  const int default_width = options.width;
  options.width = args.width.value_or(options.width);
  options.fx *= static_cast<double>(options.width) / default_width;
  options.fy *= static_cast<double>(options.width) / default_width;
  options.height = args.height.value_or(options.height);
  options.gt_object_spacing_m =
      args.gt_spacing_m.value_or(options.gt_object_spacing_m);
  options.seed = args.seed;
  if (args.noise != "kinect" && args.noise != "none") {
    throw UsageError("--noise must be 'kinect' or 'none', got '" + args.noise +
                     "'");
  }
  options.noise.enabled = args.noise == "kinect";
  options.noise.strength = args.noise_strength;
  options.noise.max_depth_m = args.max_depth_m;
  options.overwrite = args.overwrite;
  options.write_noisy_labels = args.label_noise;
  options.label_noise = args.label_noise_options;
  CheckUsage(!options.label_noise.bleed || args.label_noise,
             "--label-bleed changes the noisy labels: use it with "
             "--label-noise");
  CheckUsage(options);
  const synth::SynthSummary s =
      synth::WriteSyntheticSequence(options, args.out);
  std::string classes;
  for (const auto& [name, count] : s.objects_per_class) {
    classes += fmt::format("{}{} {}", classes.empty() ? "" : ", ", count, name);
  }
  std::string people;
  for (const auto& [n, count] : s.frames_with_people) {
    people += fmt::format("{}{} frames with {}", people.empty() ? "" : ", ",
                          count, n);
  }
  std::printf(
      "%s",
      fmt::format("preset {} (seed {}): {} frames {}x{}, {} views, "
                  "noise {} -> {}\n"
                  "objects: {}\n"
                  "people: {}{}\n"
                  "wrote {:.1f} MB in {:.1f} s\n",
                  args.preset, args.seed, s.frames, options.width,
                  options.height, args.views, args.noise, args.out, classes,
                  s.people, s.people > 0 ? " (" + people + ")" : "",
                  s.bytes_written / 1e6, s.seconds)
          .c_str());
}

}  // namespace

void RegisterSynth(CLI::App& app) {
  auto args = std::make_shared<SynthArgs>();
  CLI::App* cmd = app.add_subcommand(
      "synth",
      "Generate a synthetic RGB-D sequence (generic layout) with full ground "
      "truth: per-frame "
      "semantic, instance and person maps, exact object surfaces (meshes, "
      "dense points), people "
      "tracks (MOTChallenge gt.txt). See docs/usage.md, 'Synthetic scenes'.");
  cmd->add_option("--preset", args->preset,
                  "six-objects, people, office, flat (three rooms in a row "
                  "joined by doorways) or kitchen (rows of base cabinets "
                  "under a worktop that --label-bleed calls wall)")
      ->capture_default_str();
  cmd->add_option("--out,-o", args->out,
                  "Output folder (must be empty unless --overwrite)")
      ->required();
  cmd->add_option("--frames", args->frames,
                  "Frame count (default: the preset's)");
  cmd->add_option("--views", args->views,
                  "video: the preset's smooth camera path; sparse: independent "
                  "views at robot height (0.6-1.2 m, random heading, slight "
                  "pitch down), many objects seen once or twice")
      ->capture_default_str();
  cmd->add_option("--seed", args->seed,
                  "Random seed; equal seeds give identical files")
      ->capture_default_str();
  cmd->add_option("--noise", args->noise, "Depth noise model: kinect or none")
      ->capture_default_str();
  cmd->add_option("--noise-strength", args->noise_strength,
                  "Scales the Kinect noise sigmas")
      ->capture_default_str();
  cmd->add_option("--max-depth-m", args->max_depth_m,
                  "No depth beyond this (m)")
      ->capture_default_str();
  cmd->add_option(
      "--width", args->width,
      "Image width (default 640; the focal length 525 scales with it)");
  cmd->add_option("--height", args->height, "Image height (default 480)");
  cmd->add_option(
      "--gt-spacing-m", args->gt_spacing_m,
      "Spacing of the dense ground-truth object samples (default 0.005)");
  cmd->add_flag(
      "--label-noise", args->label_noise,
      "Also write segmenter-like labels to <out>/labels_noisy (objects "
      "cut into parts, joined with neighbours, classes flipped, "
      "ragged boundaries, small masks dropped; per view, seeded): "
      "fuse them with --labels <out>/labels_noisy");
  cmd->add_option("--label-split", args->label_noise_options.split_probability,
                  "Label noise: probability an object's mask is cut in a view")
      ->capture_default_str();
  cmd->add_option("--label-merge", args->label_noise_options.merge_probability,
                  "Label noise: probability an object's mask joins a touching "
                  "neighbour's")
      ->capture_default_str();
  cmd->add_option("--label-flip",
                  args->label_noise_options.class_flip_probability,
                  "Label noise: probability a mask gets another object class")
      ->capture_default_str();
  cmd->add_option("--label-jitter-px", args->label_noise_options.jitter_px,
                  "Label noise: boundary jitter (pixels)")
      ->capture_default_str();
  cmd->add_flag("--label-bleed", args->label_noise_options.bleed,
                "Label noise: object pixels within 20 cm of the floor or a "
                "wall, or dark, take that structure's class and mask; the "
                "same object parts in most views");
  cmd->add_option("--label-consistent-cuts",
                  args->label_noise_options.consistent_cut_share,
                  "Label noise: share of the objects with parts (chairs, "
                  "tables, sofas, beds, shelves, lamps) cut along the same "
                  "parts in 80% of the views, as a mask generator cuts a "
                  "chair's back off its seat in every view (0 = none)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--label-bleed-share", args->label_noise_options.bleed_share,
                  "Label noise: expected share of those pixels that bleed")
      ->capture_default_str();
  cmd->add_flag("--overwrite", args->overwrite,
                "Write into a non-empty output folder");
  cmd->callback([args] { RunSynth(*args); });
}

}  // namespace semrec::cli
