// The "mesh" object of scene files: every key applied, written back unchanged, each malformed
// entry refused with its JSON pointer; and the polygonizer's and improver's options that
// `zeroset mesh` and the viewer both make from the settings.
#include "zeroset/mesh/settings.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "zeroset/error.h"

namespace zeroset {
namespace {

using nlohmann::json;

TEST(MeshSettings, EveryKeyIsAppliedAndWrittenBack) {
  const json j = json::parse(R"({"cells": 40, "improve": 25, "boundary": "fix",
      "grid": "sparse", "refine_steps": 3, "curvature": false, "curvature_weight": 20.5,
      "singularity": false, "flips": false, "find_singular": false, "crossings": false,
      "curves": false, "improver": "paper"})");
  MeshSettings m;
  apply_mesh_settings(j, m, "s.json");
  EXPECT_EQ(m.cells, 40);
  EXPECT_TRUE(m.improve);
  EXPECT_EQ(m.max_improve_steps, 25);
  EXPECT_EQ(m.boundary, BoundaryMode::kFixed);
  EXPECT_EQ(m.grid, GridMode::kSparse);
  EXPECT_EQ(m.refine_steps, 3);
  EXPECT_FALSE(m.curvature);
  EXPECT_EQ(m.curvature_weight, 20.5);
  EXPECT_FALSE(m.singularity);
  EXPECT_FALSE(m.flips);
  EXPECT_FALSE(m.find_singular);
  EXPECT_FALSE(m.crossings);
  EXPECT_FALSE(m.curves);
  EXPECT_EQ(m.improver, Improver::kPaper);
  EXPECT_EQ(mesh_settings_to_json(m), j);
  MeshSettings kept = m;
  apply_mesh_settings(json::object(), kept, "s.json");
  EXPECT_EQ(mesh_settings_to_json(kept), j);
}

Improver d_improver() { return MeshSettings{}.improver; }

TEST(MeshSettings, TheOptionsOfBothFrontEndsCarryEverySetting) {
  MeshSettings m;
  m.cells = 33;
  m.grid = GridMode::kDense;
  m.refine_steps = 0;
  m.boundary = BoundaryMode::kFixed;
  m.curvature = false;
  m.curvature_weight = 3;
  m.singularity = false;
  m.flips = false;
  m.find_singular = false;
  const PolygonizeOptions po = polygonize_options(m);
  EXPECT_EQ(po.cells, 33);
  EXPECT_EQ(po.mode, GridMode::kDense);
  EXPECT_EQ(po.refine_steps, 0);
  ImproveOptions io = improve_options(m, 77);
  EXPECT_EQ(io.max_steps, 77) << "auto: the front end's limit";
  EXPECT_EQ(io.boundary, BoundaryMode::kFixed);
  EXPECT_FALSE(io.use_curvature);
  EXPECT_EQ(io.curvature_weight, 3);
  EXPECT_FALSE(io.use_singularity);
  EXPECT_FALSE(io.flip_edges);
  EXPECT_FALSE(io.find_singular_points);
  m.max_improve_steps = 12;
  EXPECT_EQ(improve_options(m, 77).max_steps, 12);
  m.improve = false;
  EXPECT_EQ(improve_options(m, 77).max_steps, 0) << "off: no step";
  // The remesher's: the boundary mode, the singular-point switch, the step limit bounds its
  // iterations. The paper's own keys are not among its options (kPaperOnlyMeshKeys).
  const RemeshOptions ro = remesh_options(m);
  EXPECT_EQ(ro.boundary, BoundaryMode::kFixed);
  EXPECT_FALSE(ro.find_singular_points);
  EXPECT_EQ(ro.max_iterations, 12);
  // The defaults are the library's.
  EXPECT_EQ(d_improver(), Improver::kRemesh);
  const MeshSettings d;
  EXPECT_EQ(polygonize_options(d).refine_steps, PolygonizeOptions{}.refine_steps);
  EXPECT_EQ(improve_options(d, 300).curvature_weight, ImproveOptions{}.curvature_weight);
}

TEST(MeshSettings, MalformedEntriesAreRefusedWithTheirPointer) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"grid": "fine"})", "/mesh/grid: expected auto, dense or sparse"},
      {R"({"grid": 1})", "/mesh/grid"},
      {R"({"improver": "cgal"})", "/mesh/improver: expected paper or remesh"},
      {R"({"improver": true})", "/mesh/improver"},
      {R"({"refine_steps": 65})", "/mesh/refine_steps: must lie in [0, 64]"},
      {R"({"refine_steps": -1})", "/mesh/refine_steps: must lie in [0, 64]"},
      {R"({"refine_steps": 2.5})", "/mesh/refine_steps: expected a whole number"},
      {R"({"curvature_weight": -1})", "/mesh/curvature_weight: must lie in [0, 1000]"},
      {R"({"curvature_weight": 1e9})", "/mesh/curvature_weight: must lie in [0, 1000]"},
      {R"({"curvature_weight": "stiff"})", "/mesh/curvature_weight: expected a number"},
      {R"({"flips": 1})", "/mesh/flips: expected true or false"},
      {R"({"curves": "no"})", "/mesh/curves: expected true or false"},
      {R"({"cells": 40, "crossings": null})", "/mesh/crossings: expected true or false"},
      {R"({"curvatur": true})", "/mesh/curvatur: unknown key"},
  };
  for (const auto& [text, where] : cases) {
    MeshSettings m;
    const MeshSettings before = m;
    try {
      apply_mesh_settings(json::parse(text), m, "s.json");
      ADD_FAILURE() << text;
    } catch (const BadInput& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("s.json: ") + where), std::string::npos)
          << text << ": " << e.what();
    }
    EXPECT_EQ(mesh_settings_to_json(m), mesh_settings_to_json(before)) << text;
  }
}

TEST(MeshSettings, GivenOptionsGoThroughTheOneReaderAndNameTheirKey) {
  MeshSettings m;
  apply_mesh_options({{"cells", 40}, {"improve", "12"}, {"crossings", false}}, m);
  EXPECT_EQ(m.cells, 40);
  EXPECT_EQ(m.max_improve_steps, 12);
  EXPECT_FALSE(m.crossings);
  auto refusal = [](const nlohmann::json& given) -> std::pair<std::string, std::string> {
    MeshSettings s;
    const MeshSettings before = s;
    try {
      apply_mesh_options(given, s);
    } catch (const SettingError& e) {
      EXPECT_EQ(mesh_settings_to_json(s), mesh_settings_to_json(before));  // all or nothing
      return {e.key(), e.why()};
    }
    return {};
  };
  EXPECT_EQ(refusal({{"cells", 0}}).first, "cells");
  EXPECT_EQ(refusal({{"cells", "64"}}),
            (std::pair<std::string, std::string>{"cells", "expected a whole number"}));
  EXPECT_EQ(refusal({{"flips", 1}}).second, "expected true or false");
  EXPECT_EQ(refusal({{"grid", "coarse"}}).first, "grid");
  EXPECT_EQ(refusal({{"cellz", 3}}).second, "is not a mesh setting");
  // The paper's own settings would do nothing with the remesher: refused when given...
  for (const char* key : {"curvature", "singularity", "flips"})
    EXPECT_EQ(refusal({{key, false}}),
              (std::pair<std::string, std::string>{key, std::string(kPaperOnlyRefusal)}));
  EXPECT_EQ(refusal({{"curvature_weight", 3}}).second, kPaperOnlyRefusal);
  // ... and taken with the paper's improver, given with it or chosen before.
  EXPECT_EQ(refusal({{"flips", false}, {"improver", "paper"}}).first, "");
  MeshSettings paper;
  paper.improver = Improver::kPaper;
  apply_mesh_options({{"flips", false}}, paper);
  EXPECT_FALSE(paper.flips);
}

}  // namespace
}  // namespace zeroset
