#pragma once
/// Floaters: particles that spread over an implicit surface F(x; q) = 0 and follow it while the
/// parameters q move (Witkin & Heckbert 1994, with the extensions of Rösch, Ruhl & Saupe 1997
/// §3: clip projection, cosine-weighted repulsion, per-particle fission radius from curvature
/// and singularity estimators). Every formula and constant is in docs/algorithms.md, sections A and
/// B; every constant is a field of FloaterOptions.
///
/// A few lines sample a surface:
/// ```cpp
/// zeroset::FloaterSystem sys(surface, {.max_count = 2000, .seed = 7});
/// for (int i = 0; i < 2000; ++i)
///   if (sys.step().converged) break;
/// zeroset::write_points_ply("floaters.ply", sys.positions(), sys.normals(), sys.radii());
/// ```
/// Interactive use (a viewer driving the system frame by frame):
/// ```cpp
/// sys.step(next_q);          // q moves to next_q during this step; F_q·q̇ keeps floaters on F = 0
/// draw(sys.positions(), sys.normals(), sys.radii());
/// sys.set_options(o);        // any option may change between steps (heuristics on/off, σ̂, cap)
/// sys.reset();               // start again from random seeding
/// ```
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <stop_token>
#include <string>
#include <string_view>
#include <vector>

#include "zeroset/surface/surface.h"
#include "zeroset/types.h"

namespace zeroset {

/// How each floater's fission radius σ_max^i = μ_i σ_max is chosen (Rösch et al. §3.3).
enum class RadiusAdapt {
  kWitkinHeckbert,  ///< μ_i = 1: one global σ_max, the original method
  kCurvature,       ///< μ_i = α_i, the curvature estimator
  kSingular,        ///< μ_i = β_i, the distance-to-singularity estimator
  kMixed,           ///< μ_i = α_i/3 + 2β_i/3 (the paper's choice)
};

/// Parses "wh", "curvature", "singular" or "mixed". Throws InvalidArgument naming `flag`.
RadiusAdapt parse_radius_adapt(std::string_view text, std::string_view flag = "radius_adapt");
/// The name parse_radius_adapt accepts.
std::string_view to_string(RadiusAdapt mode);

/// Settings of a FloaterSystem. Lengths are in world units, times in the system's time unit
/// (one step advances time by `dt`). Defaults are those of docs/algorithms.md, sections A and B.
struct FloaterOptions {
  // --- population -------------------------------------------------------------------------
  /// σ̂, the nominal repulsion radius: the density knob (spacing at equilibrium ≈ 1.5σ̂).
  /// 0: chosen from the surface's area (estimate_area) so that about `max_count`/3 floaters
  /// would cover it uniformly, leaving room for the refinement near singular points.
  /// Kept within [1e-9, 1] × the scene radius.
  double radius = 0;
  std::size_t max_count = 2000;  ///< population cap: no fission beyond it
  /// Random insertions into the clip volume at the start and after reset() (paper §3.4). The
  /// system also reinserts them whenever it has become empty. 0: min(max_count, 200).
  std::size_t seed_count = 0;
  std::uint64_t seed = 1;  ///< every random choice derives from it: same seed, same result

  // --- dynamics (Witkin–Heckbert 94) ----------------------------------------------------------
  double dt = 0.03;                    ///< Euler time step
  double repulsion = 6;                ///< α, amplitude of the pair energy
  double desired_energy_factor = 0.8;  ///< Ê = factor·α
  double radius_rate = 15;             ///< ρ, rate of the radius adaptation
  double radius_damping = 10;          ///< β of A.3, keeps dσ/dt finite for lone floaters
  /// φ, pull of the φF term towards F = 0: the distance to F = 0 shrinks by a factor
  /// (1 − φ·dt) per step, so φ·dt must stay below 2 (validate_settings); φ·dt ≤ 1 does not
  /// overshoot.
  double feedback = 15;
  /// The tangential move of one step is at most this fraction of σ_i (stability).
  double max_step_fraction = 0.5;
  /// γ: near equilibrium when |ṗ_i| < γσ_i. Positive, and at most max_step_fraction/dt: a
  /// tangential move never exceeds max_step_fraction·σ_i per step, so beyond that every
  /// floater would count as near equilibrium however fast it moves.
  double equilibrium_speed = 4;
  /// Fission and death use the local nominal radius σ̂_i = min(σ̂, σ_max^i), so floaters made
  /// small near a singular point are not killed for being small. Off: the paper's σ̂ in both
  /// tests (docs/algorithms.md A.7), so floaters below δσ̂ near a singular point die.
  bool local_nominal_radius = true;
  /// The fission child starts at a random tangential offset of 0.25σ_i to 0.5σ_i. Off:
  /// Witkin–Heckbert's plain split, the child where its parent is (the pair forces separate
  /// the twins along a direction derived from their ids).
  bool fission_offset = true;
  double fission_energy_factor = 0.2;  ///< ν: energised fission when E_i > νÊ and σ_i > σ̂_i
  double death_radius_factor = 0.7;    ///< δ: death candidate when σ_i < δσ̂_i
  double max_radius_factor = 1.5;      ///< σ_max = factor·σ̂ (fission whenever σ_i > σ_max^i)
  /// Pair forces use the pair's mean radius σ_ij = (σ_i + σ_j)/2 and scale with it:
  /// P_i = σ_i Σ_j (r_ij/σ_ij) 2E(r_ij; σ_ij), the same as A.2 when all radii are equal. Then a
  /// graded density (smaller σ_max^i near singular points) is an equilibrium; with A.2 the
  /// dense side always pushes floaters towards the sparse side, and fission there and death
  /// elsewhere never stop. false: A.2 exactly.
  bool scaled_repulsion = true;
  /// The energy's taper (1 − |r|²/9σ²), which takes E_ij and its force to zero at the cutoff
  /// 3σ. Off: Witkin–Heckbert's plain Gaussian α e^(−|r|²/2σ²), still cut off at 3σ (where it
  /// has fallen to 1.1% of its peak) so the neighbour search stays finite.
  bool energy_taper = true;

  // --- Rösch–Ruhl–Saupe 97 extensions (each can be switched off) ------------------------------
  /// §3.2: a floater that leaves the clip volume is projected back onto its boundary (then
  /// moved along the boundary onto F = 0, so it stays on the surface). Off: it is removed
  /// (the unclipped method loses floaters over the boundary).
  bool clip_projection = true;
  /// After that projection, up to two Newton steps along the clip boundary put the floater on
  /// the curve F = 0 ∩ ∂clip (docs/algorithms.md A.6). Off: the paper's projection alone, and
  /// floaters on the boundary stay off F = 0 (pushed out and projected back every step).
  bool clip_newton = true;
  /// §3.3: E_ij is weighted by |cos(∇F_i, ∇F_j)|, so sheets pass through each other.
  bool cos_weight = true;
  RadiusAdapt radius_adapt = RadiusAdapt::kMixed;  ///< §3.3: per-particle σ_max^i = μ_i σ_max
  /// μ_i is averaged with its previous value at each refresh, μ_i ← (μ_i + clamp(f))/2, since
  /// α_i comes from random perimeter points. Off: the paper's μ_i = clamp(f), the estimate of
  /// this refresh alone.
  bool average_radius_factor = true;
  /// α_i and β_i (and node snapping) are refreshed every this many steps (in [1, 1000]).
  int estimator_interval = 8;
  int curvature_samples = 4;  ///< random perimeter points for α_i
  /// γ_s of β_i = min(|r|/γ_s, 1), in world units. 0: scene_radius/3 (= 1 on the paper's
  /// Kummer scene, the value it used).
  double singular_scale = 0;
  /// A floater that comes within half its radius of a node (a nondegenerate singular point,
  /// found by the β estimator's Newton step and Newton's method on ∇F = 0) is moved onto it and
  /// stays there, following it while the parameters move: every node carries a floater, drawn
  /// as the cone tip it is. The same switch holds floaters on the rest of the singular set
  /// (docs/algorithms.md B.7): one on each pinch, triple, clip-end or degenerate point, and
  /// chains spaced along its curves, once the parameters are still.
  bool snap_to_nodes = true;
  /// μ_i is kept at least this large, so σ_max^i never collapses to zero at a singular point.
  double min_radius_factor = 0.2;
  /// Grading g of the fission radii: σ_max^i ≤ σ_max^j + g·|p_i − p_j| for neighbours, so the
  /// wanted density changes gradually where μ_i jumps and fission and death do not fight.
  /// 0: off (the paper's raw σ_max^i).
  double radius_grading = 0.1;

  // --- convergence ----------------------------------------------------------------------------
  // With per-particle fission radii the equilibrium is dynamic: a trickle of fissions near
  // singular points and deaths elsewhere never stops entirely. "Settled" is therefore judged
  // over a window of steps (StepStats::converged):
  int converge_window = 50;  ///< steps looked back over
  /// Births + deaths + removals + insertions per floater per step, averaged over the window,
  /// at most this (0.002: two floaters in a thousand per step)...
  double converge_churn = 0.002;
  /// ...the population within 1% of what it was at the start of the window, and the RMS
  /// floater speed, averaged over the window, below this many radii per time unit.
  double converge_speed = 1.0;

  /// OpenMP threads for one step; 0: OpenMP's default (all cores). Systems of fewer than
  /// 4,096 floaters step on one thread (a parallel region would cost more than it saves).
  int threads = 0;
};

/// What one step did, and the state after it.
struct StepStats {
  std::size_t step = 0;     ///< steps taken so far, this one included
  std::size_t count = 0;    ///< floaters after the step
  std::size_t births = 0;   ///< fissions
  std::size_t deaths = 0;   ///< deaths by the randomised density rule
  std::size_t removed = 0;  ///< strays (far from F = 0, degenerate σ, or outside the clip)
  /// Of those, floaters removed because F or ∇F was not finite where they went (a pole, a NaN
  /// region) or they left the clip.
  std::size_t undefined_removed = 0;
  std::size_t inserted = 0;  ///< random insertions (start, reset, or an empty system)
  /// |F|/|∇F| at the floaters after the step (first-order distance; infinite-free: a floater
  /// with ∇F = 0 and F ≠ 0 counts as the largest double), floaters held on nodes left out. 0
  /// when there are none.
  double median_residual = 0;
  double max_residual = 0;
  double rms_speed = 0;  ///< RMS over the floaters of |ṗ_i|/σ_i (radii per time unit)
  std::size_t near_equilibrium = 0;  ///< floaters with |ṗ_i| < γσ_i
  /// Over the last `converge_window` steps: population events at most converge_churn per
  /// floater per step, the count within 1% of its value a window ago, and the mean rms_speed
  /// below converge_speed (FloaterOptions).
  bool converged = false;
  double seconds = 0;  ///< wall time of the step
};

/// A system of floaters on one surface. Not thread-safe: one thread drives it; step() itself
/// runs in parallel (OpenMP) with a result that depends only on the seed, never on the number
/// of threads (per-floater random streams from seed + floater id + step; fission and death in
/// a serial pass). Cost of a step: O(n) for n floaters (spatial hash rebuilt each step); the
/// curvature and singularity estimators add a few field evaluations per floater every
/// `estimator_interval` steps.
class FloaterSystem {
 public:
  /// Seeds `seed_count` random floaters in the surface's clip volume. With options.radius = 0
  /// the surface's area is estimated first (tens of milliseconds). Throws BadInput when the
  /// clip is unbounded or a parameter has no value, InvalidArgument for a bad option (named).
  /// Once `stop` is requested, the area estimate and the singular set search (here and in
  /// later calls) end early with what they have: a system stopped so is only fit to be
  /// discarded, as a background job does when it is cancelled.
  FloaterSystem(const Surface& surface, const FloaterOptions& options = {},
                std::stop_token stop = {});
  ~FloaterSystem();
  FloaterSystem(FloaterSystem&&) noexcept;
  FloaterSystem& operator=(FloaterSystem&&) noexcept;

  /// One Euler step with the parameters held fixed.
  StepStats step();
  /// One step while the parameters move linearly to `next_parameters` (one value per
  /// parameter of the field, in its order): q̇ = (next − current)/dt enters the F_q·q̇ term of
  /// the constrained velocity, and afterwards parameters() == next_parameters. Throws
  /// InvalidArgument for a wrong count or a non-finite value.
  StepStats step(std::span<const double> next_parameters);

  /// Sets the parameters at once, without the F_q·q̇ term (floaters re-settle through φF).
  void set_parameters(std::span<const double> values);
  /// Sets one parameter by name at once. Throws InvalidArgument for an unknown name.
  void set_parameter(std::string_view name, double value);
  std::span<const double> parameters() const;

  /// Replaces the surface (a new equation or clip), keeping the floaters' positions (projected
  /// into the new clip, radii reset to σ̂); they settle on the new surface. The nominal radius
  /// is recomputed when options().radius is 0. Throws as the constructor does.
  void set_surface(const Surface& surface);
  const Surface& surface() const;

  /// Changes options between steps (validated as in the constructor; throws InvalidArgument
  /// and keeps the old ones). Lowering max_count removes the floaters beyond it; a new seed
  /// takes effect for random choices from now on.
  void set_options(const FloaterOptions& options);
  const FloaterOptions& options() const;

  /// Removes every floater and seeds again with the current seed: the state after
  /// construction, for the current parameters.
  void reset();
  /// reset() with another seed.
  void reseed(std::uint64_t seed);

  /// σ̂ in use (options().radius, or the value chosen from the area).
  double nominal_radius() const;
  std::size_t size() const;
  std::size_t steps_taken() const;
  /// Floater state after the last step, all of length size(), in an order that changes from
  /// step to step (floaters are kept sorted by spatial cell); ids() follows them. The spans
  /// stay valid until the next call that changes the system.
  std::span<const Vec3> positions() const;
  std::span<const double> radii() const;  ///< σ_i
  /// Unit ∇F at each position ((0,0,1) where ∇F = 0): the orientation for drawing. Built on
  /// the first call after a change (O(n), no field evaluation).
  std::span<const Vec3> normals() const;
  /// Unique per floater since construction or the last reset() (which numbers afresh).
  std::span<const std::uint64_t> ids() const;
  /// σ_max^i, the fission radius of each floater (μ_i σ_max after grading; σ_max everywhere
  /// with RadiusAdapt::kWitkinHeckbert).
  std::span<const double> max_radii() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace zeroset
