// Ray casting of a synthetic scene into RGB, metric depth and label maps.
#pragma once

#include "semrec/core/camera.h"
#include "semrec/core/image.h"
#include "semrec/core/label_map.h"
#include "semrec/core/transform.h"
#include "semrec/synth/scene.h"

namespace semrec::synth {

/// Everything one camera sees at one instant, noise-free.
struct RenderedFrame {
  ColorImage color;
  /// Exact z-depth (m) along the camera's optical axis; 0 where no surface is
  /// hit.
  DepthImage depth;
  /// |cos| of the angle between the viewing ray and the surface normal (for
  /// grazing dropout).
  Image<float> cos_incidence;
  /// Class id per pixel (SynthClasses()).
  LabelMap semantic;
  /// Instance id per pixel: objects 1..999, people kPersonInstanceBase + person
  /// id.
  LabelMap instance;
  /// Person id per pixel, 0 = no person.
  LabelMap person;
  /// 1-based index of the object's primitive (SceneObject::parts) per pixel;
  /// 0 for structure, people and background.
  LabelMap part;
};

/// Renders `scene` at `time_s` (people move) from T_world_camera with
/// intrinsics `k`.
RenderedFrame Render(const Scene& scene, double time_s,
                     const Transform& T_world_camera,
                     const CameraIntrinsics& k);

/// Number of pixels person `person_id` would cover with nothing in front of it
/// (for the MOT visibility ratio), and its unoccluded bounding box (x0, y0, x1,
/// y1) inclusive.
struct Silhouette {
  size_t pixels = 0;
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
};
Silhouette UnoccludedSilhouette(const Scene& scene, uint16_t person_id,
                                double time_s, const Transform& T_world_camera,
                                const CameraIntrinsics& k);

}  // namespace semrec::synth
