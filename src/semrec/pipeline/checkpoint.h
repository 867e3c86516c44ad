// Checkpoints of a `semrec run`: what rebuilds the pipeline's state without
// the models. Per finished frame the models' outputs are kept (static labels,
// the tracker's input detections with embeddings, the people's id map; label
// maps as lossless PNG); state.json names how many frames are final, and is
// written atomically after their files. Resuming replays those frames through
// fusion, volumes and the tracker (milliseconds per frame, no model runs),
// which gives exactly the state an uninterrupted run had, then continues.
//
// Layout: <out>/checkpoint/identity.json (sequence, frame count, config hash),
// state.json, frames/<position>.json and frames/<position>_{semantic,instance,
// person}.png.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "semrec/pipeline/scene_pipeline.h"

namespace semrec::pipeline {

/// What a checkpoint must match: the sequence and the effective options.
struct RunIdentity {
  std::string sequence;
  std::string layout;
  size_t frames = 0;
  /// sha256 of the effective configuration text.
  std::string config_sha256;
  nlohmann::json ToJson() const;
};

/// A frame as the checkpoint holds it.
struct CheckpointFrame {
  /// The frame could not be read (skipped, with this reason).
  std::optional<std::string> skipped;
  /// Model outputs (models mode), to replay.
  std::optional<ModelOutputs> outputs;
};

class CheckpointStore {
 public:
  explicit CheckpointStore(std::filesystem::path dir);

  /// A fresh run: removes an old checkpoint and records `identity`.
  void Start(const RunIdentity& identity);
  /// A resumed run: throws InvalidArgument, saying what differs, when the
  /// checkpoint was made for another sequence or other options, IoError when
  /// there is none. Returns how many frames are final.
  size_t Resume(const RunIdentity& identity) const;

  /// Keeps frame `position`'s record (not final until Commit()).
  void Record(size_t position, const CheckpointFrame& frame) const;
  /// Frames [0, frames_done) are final.
  void Commit(size_t frames_done) const;
  /// Frame `position`'s record; throws FormatError naming the file when it is
  /// damaged.
  CheckpointFrame Load(size_t position) const;

  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path FramePath(size_t position,
                                  const std::string& suffix) const;
  std::filesystem::path dir_;
};

}  // namespace semrec::pipeline
