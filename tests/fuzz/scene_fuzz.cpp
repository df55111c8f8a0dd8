// libFuzzer target: read arbitrary bytes as a scene file (JSON, and as a SURFER .jsurf file),
// then write the scene and read it again. Any crash, hang, sanitizer report or escaped
// exception other than BadInput is a bug: a bad file is refused with a message, and a scene
// that was read once must survive its own save.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "zeroset/error.h"
#include "zeroset/surface/json_read.h"
#include "zeroset/surface/jsurf.h"
#include "zeroset/surface/keyframes.h"
#include "zeroset/surface/scene.h"

namespace {

void use(const zeroset::Scene& scene) {
  // What every command does next with a scene: its ranges, bounds and keyframes.
  const zeroset::Surface& s = scene.surface;
  for (const zeroset::ParamSpec& r : s.ranges)
    if (!(r.max - r.min < 1e300)) __builtin_trap();  // a slider's span must be finite
  if (s.clip.is_bounded()) (void)s.scene_radius();
  try {
    (void)zeroset::read_keyframes(scene.settings, s, 10, "fuzz");
  } catch (const zeroset::BadInput&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  zeroset::Scene scene;
  try {
    scene = zeroset::scene_from_json(zeroset::json_read::parse(text, "fuzz"), "fuzz");
  } catch (const zeroset::BadInput&) {
    try {
      scene = zeroset::jsurf_to_scene(text, "fuzz.jsurf");
    } catch (const zeroset::BadInput&) {
      return 0;
    }
  }
  use(scene);
  // Saved and read again: must be accepted (a file the viewer writes must load).
  const std::string saved = zeroset::scene_to_json(scene).dump(2);
  const zeroset::Scene again =
      zeroset::scene_from_json(zeroset::json_read::parse(saved, "saved"), "saved");
  use(again);
  if (again.surface.ranges.size() != scene.surface.ranges.size()) __builtin_trap();
  return 0;
}
