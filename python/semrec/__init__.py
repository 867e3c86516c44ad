"""semrec: RGB-D frames with poses in, a semantically labelled, instance-tracked 3D scene (USD) out.

    import semrec
    seq = semrec.open_sequence("7scenes_chess_0_99")
    pipe = semrec.Pipeline()                      # the default models
    for frame in seq:
        pipe.add_frame(frame.color, frame.depth, frame.K, frame.T_world_camera)
    pipe.finish()
    print([(o["id"], o["class"], len(o["points"])) for o in pipe.objects()])
    pipe.write("out")

Arrays are numpy: colour H x W x 3 uint8, depth H x W float32 metres (or uint16 with
depth_scale), K 3 x 3 and T_world_camera 4 x 4 float64 (camera to world). Errors: ValueError for
bad options and shapes, TypeError for wrong dtypes, semrec.FormatError / semrec.IoError (OSErrors
naming the file) for bad files.
"""
from ._semrec import (  # noqa: F401
    Error,
    FormatError,
    Frame,
    IoError,
    Pipeline,
    Segmenter,
    Sequence,
    eval,
    load,
    run,
    set_log_level,
)

__all__ = ["Error", "FormatError", "Frame", "IoError", "Pipeline", "Segmenter", "Sequence", "eval", "load", "open_sequence",
           "segment",
           "run", "set_log_level"]


def open_sequence(path, stride=1, max_frames=0, max_depth_m=0.0, labels=None):
    """Opens an RGB-D sequence (layout detected: semrec manifest, TUM, Redwood, 7-Scenes).

    labels: None, "gt" (the sequence's own label layers, e.g. `semrec synth` output) or a label
    folder (`semrec segment` output): frames then carry .semantic / .instance (and .person).
    Returns a Sequence: len(), indexing (negative too), iteration over Frames.
    """
    return Sequence(str(path), stride, max_frames, max_depth_m,
                    None if labels is None else str(labels))



_segmenter = None


def segment(image):
    """Segments one RGB image (H x W x 3 uint8) with the default models (loaded on the first call).

    Returns dict(semantic=H x W uint16 class ids, instance=H x W uint16, classes={id: name},
    masks=count). For other options make a semrec.Segmenter(...) and call it.
    """
    global _segmenter
    if _segmenter is None:
        _segmenter = Segmenter()
    return _segmenter(image)
