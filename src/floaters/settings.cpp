#include "zeroset/floaters/settings.h"

#include "zeroset/error.h"
#include "zeroset/surface/json_read.h"

namespace zeroset {
namespace {

using nlohmann::json;

using json_read::boolean;
using json_read::fail;
using json_read::whole;

double non_negative(const json& j, const std::string& origin, const std::string& path) {
  const double v = json_read::number(j, origin, path);
  if (v < 0) fail(origin, path, "must not be negative");
  return v;
}

}  // namespace

void apply_floater_settings(const json& floaters, FloaterOptions& options,
                            const std::string& origin) {
  const std::string base = "/floaters";
  if (!floaters.is_object()) fail(origin, base, "expected an object");
  FloaterOptions o = options;
  for (const auto& [key, value] : floaters.items()) {
    const std::string p = base + "/" + key;
    if (key == "max_count")
      o.max_count = whole(value, origin, p, 1, 1e8);
    else if (key == "seed_count")
      o.seed_count = whole(value, origin, p, 0, 1e8);
    else if (key == "seed")
      o.seed = whole(value, origin, p, 0, 9007199254740992.0);
    else if (key == "radius")
      o.radius = non_negative(value, origin, p);
    else if (key == "radius_grading")
      o.radius_grading = non_negative(value, origin, p);
    else if (key == "cos_weight")
      o.cos_weight = boolean(value, origin, p);
    else if (key == "clip_projection")
      o.clip_projection = boolean(value, origin, p);
    else if (key == "snap_to_nodes")
      o.snap_to_nodes = boolean(value, origin, p);
    else if (key == "scaled_repulsion")
      o.scaled_repulsion = boolean(value, origin, p);
    else if (key == "radius_adapt") {
      try {
        o.radius_adapt = parse_radius_adapt(json_read::string(value, origin, p), p);
      } catch (const InvalidArgument&) {
        fail(origin, p, "expected wh, curvature, singular or mixed");
      }
    } else {
      fail(origin, p,
           "unknown key (known: max_count, seed_count, seed, radius, radius_grading, "
           "cos_weight, clip_projection, snap_to_nodes, scaled_repulsion, radius_adapt)");
    }
  }
  options = o;
}

json floater_settings_to_json(const FloaterOptions& o) {
  return {{"max_count", o.max_count},
          {"seed_count", o.seed_count},
          {"seed", o.seed},
          {"radius", o.radius},
          {"radius_grading", o.radius_grading},
          {"cos_weight", o.cos_weight},
          {"clip_projection", o.clip_projection},
          {"snap_to_nodes", o.snap_to_nodes},
          {"scaled_repulsion", o.scaled_repulsion},
          {"radius_adapt", std::string(to_string(o.radius_adapt))}};
}

}  // namespace zeroset
