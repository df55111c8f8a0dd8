// The statistics of a mesh run as JSON (MeshResult::to_json): the `--stats` file of
// `zeroset mesh` and the dictionary of Python's Surface.mesh (docs/meshing.md, "Statistics").
#include <nlohmann/json.hpp>

#include "zeroset/mesh/mesh_surface.h"
#include "zeroset/surface/json_read.h"

namespace zeroset {
namespace {

using json = nlohmann::json;

json polygonize_json(const MeshResult& r) {
  const PolygonizeStats& ps = r.polygonize;
  return {{"resolution", r.settings.cells},
          {"cells", ps.cells},
          {"cell_size", ps.cell_size},
          {"grid", ps.sparse ? "sparse" : "dense"},
          {"bricks", ps.bricks},
          {"bricks_kept", ps.bricks_kept},
          {"grid_samples", ps.grid_samples},
          {"refine_evaluations", ps.refine_evaluations},
          {"nan_samples", ps.nan_samples},
          {"undefined_edges", ps.undefined_edges},
          {"pole_edges", ps.pole_edges},
          {"undefined_triangles", ps.undefined_triangles},
          {"active_cells", ps.active_cells},
          {"ambiguous_faces", ps.ambiguous_faces},
          {"edge_vertices", ps.edge_vertices},
          {"welded_vertices", ps.welded_vertices},
          {"collapsed_edges", ps.collapsed_edges},
          {"clip_cut_edges", ps.clip_cut_edges},
          {"clip_snapped_vertices", ps.clip_snapped},
          {"seconds",
           {{"sampling", ps.seconds_sampling},
            {"extraction", ps.seconds_extraction},
            {"refinement", ps.seconds_refinement},
            {"cleanup", ps.seconds_cleanup},
            {"total", ps.seconds_total}}},
          {"vertices", r.polygonized_vertices},
          {"triangles", r.polygonized_triangles}};
}

json points_json(const std::vector<Vec3>& points) {
  json a = json::array();
  for (const Vec3& p : points) a.push_back(json_read::from_vec3(p));
  return a;
}

json crossings_json(const CrossingStats& cs) {
  json left = json::array();
  for (const CrossingStats::Place& p : cs.left_as_marching_cubes)
    left.push_back({{"at", json_read::from_vec3(p.at)}, {"radius", p.radius}});
  return {{"crossing_curves", cs.crossing_curves},
          {"isolated_curves", cs.isolated_curves},
          {"curve_vertices", cs.curve_vertices},
          {"removed_triangles", cs.removed_triangles},
          {"added_triangles", cs.added_triangles},
          {"strip_vertices", cs.strip_vertices},
          {"left_as_marching_cubes", left},
          {"failure", cs.failure},
          {"seconds", cs.seconds}};
}

json quality_json(const MeshQuality& q) {
  json j;
  j["vertices"] = q.vertices;
  j["triangles"] = q.triangles;
  j["mean_edge_length"] = q.mean_edge_length;
  j["min_angle_histogram"] = {{"bin_width_deg", 5}, {"counts", q.min_angle_histogram}};
  j["percent_min_angle_below_10"] = q.percent_below_10;
  j["percent_min_angle_below_20"] = q.percent_below_20;
  j["percent_min_angle_below_30"] = q.percent_below_30;
  j["mean_min_angle_deg"] = q.mean_min_angle_deg;
  j["smallest_angle_deg"] = q.smallest_angle_deg;
  j["zero_area_triangles"] = q.zero_area_triangles;
  j["coincident_vertices"] = q.coincident_vertices;
  j["radius_ratio"] = {{"mean", q.mean_radius_ratio}, {"min", q.min_radius_ratio}};
  j["residual"] = {{"max", q.max_residual},
                   {"rms", q.rms_residual},
                   {"vertices", q.residual_vertices},
                   {"undefined_vertices", q.undefined_vertices},
                   {"excluded_radius_around_singular_points", q.singular_radius}};
  j["normal_deviation_deg"] = {{"mean", q.mean_normal_deviation_deg},
                               {"max", q.max_normal_deviation_deg},
                               {"flipped_triangles", q.flipped_triangles}};
  j["boundary"] = {{"vertices", q.boundary_vertices},
                   {"max_abs_clip_value", q.max_boundary_clip_value}};
  json sing = json::array();
  for (size_t k = 0; k < q.singular_points.size(); ++k)
    sing.push_back(
        {{"point", json_read::from_vec3(q.singular_points[k])},
         {"nearest_vertex_distance", q.singular_point_distance[k]},
         {"in_mean_edge_lengths",
          q.mean_edge_length > 0 ? q.singular_point_distance[k] / q.mean_edge_length : 0.0}});
  j["singular_points"] = sing;
  return j;
}

json topology_json(const MeshTopology& t) {
  return {{"vertices", t.vertices},
          {"edges", t.edges},
          {"triangles", t.triangles},
          {"boundary_edges", t.boundary_edges},
          {"non_manifold_edges", t.non_manifold_edges},
          {"misoriented_edges", t.misoriented_edges},
          {"euler_characteristic", t.euler_characteristic},
          {"watertight", t.is_watertight()}};
}

}  // namespace

json MeshImprovement::to_json() const {
  const std::string boundary_name(to_string(boundary));
  if (improver == Improver::kRemesh) {
    const RemeshStats& rs = remesh;
    return {{"improver", "remesh"},
            {"iterations", rs.iterations},
            {"max_iterations", remesh_options.max_iterations},
            {"converged", rs.converged},
            {"target_edge", rs.target_edge},
            {"splits", rs.splits},
            {"collapses", rs.collapses},
            {"flips", rs.flips},
            {"refused_collapses", rs.refused_collapses},
            {"relax_steps", rs.relax_steps},
            {"reverted_moves", rs.reverted_moves},
            {"last_max_move_in_target_edges", rs.last_max_move},
            {"singular_points_held", points_json(rs.singular_points)},
            {"missed_singular_points", rs.missed_singular_points},
            {"pinch_held_vertices", rs.pinch_held_vertices},
            {"pinch_improver_steps", rs.pinch_improver_steps},
            {"max_residual", rs.max_residual},
            {"undefined_vertices", rs.undefined_vertices},
            {"boundary", boundary_name},
            {"find_singular_points", remesh_options.find_singular_points},
            {"seconds", rs.seconds}};
  }
  const ImproveStats& is = paper;
  const ImproveOptions& io = paper_options;
  return {{"improver", "paper"},
          {"steps", is.steps},
          {"max_steps", io.max_steps},
          {"converged", is.converged},
          {"last_max_move_in_mean_edges", is.max_move},
          {"edge_flips", is.flips},
          {"shortened_moves", is.shortened_moves},
          {"cancelled_moves", is.cancelled_moves},
          {"flipped_triangles", is.flipped_triangles},
          {"singular_points_found", points_json(is.singular_points)},
          {"max_residual", is.max_residual},
          {"refused_moves", is.refused_moves},
          {"undefined_vertices", is.undefined_vertices},
          {"boundary", boundary_name},
          {"curvature", io.use_curvature},
          {"curvature_weight", io.curvature_weight},
          {"singularity", io.use_singularity},
          {"flips", io.flip_edges},
          {"find_singular_points", io.find_singular_points},
          {"seconds", is.seconds}};
}

json MeshResult::to_json() const {
  json stats;
  stats["surface"] = surface.label();
  json params = json::object();
  const auto& names = surface.field.parameter_names();
  for (size_t k = 0; k < names.size(); ++k) params[names[k]] = surface.field.parameter_values()[k];
  stats["parameters"] = params;
  stats["clip"] = surface.clip.to_specs();
  if (survey) stats["field"] = survey_json(*survey);
  stats["polygonize"] = polygonize_json(*this);
  stats["singular_set"] = singular ? singular_set_json(*singular, false) : json();
  if (crossings) stats["crossings"] = crossings_json(*crossings);
  if (quality_before) stats["quality_before"] = quality_json(*quality_before);
  if (topology_before) stats["topology_before"] = topology_json(*topology_before);
  if (improvement) stats["improve"] = improvement->to_json();
  if (quality_after) stats["quality_after"] = quality_json(*quality_after);
  if (topology_after) stats["topology_after"] = topology_json(*topology_after);
  stats["seconds_total"] = seconds;
  return stats;
}

}  // namespace zeroset
