#include <nlohmann/json.hpp>

#include "zeroset/render/render.h"

namespace zeroset {

nlohmann::json RenderStats::to_json() const {
  return {{"threads", threads},
          {"method", exact ? "polynomial roots" : "interval arithmetic"},
          {"seconds", seconds},
          {"rays", rays},
          {"hits", hits},
          {"singular_normals", singular_normals},
          {"abandoned_rays", abandoned_rays},
          {"accurate_rays", accurate_rays}};
}

}  // namespace zeroset
