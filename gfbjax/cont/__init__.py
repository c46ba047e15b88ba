"""Generic numerical continuation of equilibria and periodic orbits in JAX.

The engine knows nothing about bearings: it works for any autonomous ``f(x, lam, args)`` (a pure JAX function;
``args`` any pytree).  This module is its public face; the modules behind it are private and may move.

Layers, bottom up:

* problems and results: :class:`CycleProblem`, :class:`EquilibriumProblem`; :class:`Branch` (struct of arrays,
  npz + JSON, xarray/netCDF; :class:`BranchFileError` for a file that cannot be read), :class:`Checkpoint`
  (a folder a continuation appends every step to and resumes from; :class:`CheckpointError`), :class:`SpecialPoint`,
  :class:`Outcome` (one vocabulary for every solver and branch end);
* collocation: :class:`Scheme`, :class:`Orbit`, constraints (Gauss collocation, condensation of parameters);
* linear solvers behind one protocol (:class:`DenseCondensation`, :class:`SparseSweep`): solve, transposed solve,
  transfer matrices, monodromy operator;
* one Newton corrector (:func:`newton_solve` compiled, :func:`newton_solve_host` from Python,
  :class:`NewtonSettings`);
* one continuation driver for equilibria and cycles (:func:`continue_equilibria`, :func:`continue_cycles`) with
  the algorithms :class:`PseudoArclength` and :class:`Natural`, test functions and their localisation;
* Floquet methods (:class:`PeriodicQR`, :class:`TransferProduct`, :class:`BlockKrylov`, :class:`Arnoldi`);
* implicit derivatives through converged cycles (tangent and adjoint modes), batched (vmapped) corrections.

Precision: the engine expects ``jax_enable_x64`` (``import gfbjax`` turns it on).
"""
from ._batch import BatchNewtonResult as BatchNewtonResult, batched_newton as batched_newton
from ._branch import Branch as Branch, BranchFileError as BranchFileError, PointRecord as PointRecord
from ._checkpoint import Checkpoint as Checkpoint, CheckpointError as CheckpointError
from ._collocation import (Constraint as Constraint, Orbit as Orbit, Scheme as Scheme,
                           dense_newton_step as dense_newton_step, natural_constraint as natural_constraint,
                           orbit_from_function as orbit_from_function, orbit_from_samples as orbit_from_samples,
                           palc_constraint as palc_constraint, transfer_matrices as transfer_matrices,
                           uniform_mesh as uniform_mesh)
from ._cycles import (CycleStart as CycleStart, analyse as analyse, bind_solver as bind_solver,
                      check_cycle_inputs as check_cycle_inputs, check_cycle_size as check_cycle_size,
                      continue_cycles as continue_cycles, correct_cycle as correct_cycle,
                      start_from_branch as start_from_branch,
                      start_from_function as start_from_function, start_from_hopf as start_from_hopf,
                      start_from_pd as start_from_pd, start_from_samples as start_from_samples)
from ._localise import locate as locate
from ._equilibria import HopfPoint as HopfPoint, continue_equilibria as continue_equilibria, hopf_point as hopf_point
from ._floquet import (Arnoldi as Arnoldi, BlockKrylov as BlockKrylov, FloquetMethod as FloquetMethod, PeriodicQR as PeriodicQR,
                       PeriodicQRResult as PeriodicQRResult, TransferProduct as TransferProduct,
                       multipliers_periodic as multipliers_periodic, multipliers_product as multipliers_product,
                       nontrivial as nontrivial, trivial_error as trivial_error)
from ._implicit import (adjoint_gradient as adjoint_gradient, functional_derivatives as functional_derivatives,
                        leading_multiplier as leading_multiplier, multiplier_derivatives as multiplier_derivatives,
                        multiplier_gradient as multiplier_gradient, orbit_sensitivities as orbit_sensitivities)
from ._linear import (DenseCondensation as DenseCondensation, Linearisation as Linearisation,
                      LinearSolver as LinearSolver, SPARSE_MIN_N as SPARSE_MIN_N, SparseSweep as SparseSweep)
from ._newton import (LinearSolveError as LinearSolveError, NewtonSettings as NewtonSettings,
                      NewtonSolution as NewtonSolution, solve as newton_solve, solve_host as newton_solve_host)
from ._problem import CycleProblem as CycleProblem, EquilibriumProblem as EquilibriumProblem, Monitor as Monitor
from ._resolution import (halved_error as halved_error, mode_error as mode_error, multiplier_estimates as multiplier_estimates,
                          resolution as resolution)
from ._results import Outcome as Outcome, SPECIAL_TYPES as SPECIAL_TYPES, SpecialPoint as SpecialPoint
from ._settings import (CycleSettings as CycleSettings, EquilibriumSettings as EquilibriumSettings,
                        Natural as Natural, PseudoArclength as PseudoArclength)
from ._sparsity import (Coloring as Coloring, color_pattern as color_pattern, dense_jacobian as dense_jacobian,
                        jacobian_values as jacobian_values)

__all__ = [
    "resolution", "mode_error", "halved_error", "multiplier_estimates", "Arnoldi", "BatchNewtonResult", "BlockKrylov", "check_cycle_inputs", "check_cycle_size", "Branch", "BranchFileError", "Checkpoint", "CheckpointError", "Monitor", "Coloring", "Constraint", "CycleProblem",
    "CycleSettings", "CycleStart",
    "DenseCondensation", "EquilibriumProblem", "EquilibriumSettings", "FloquetMethod", "HopfPoint",
    "LinearSolveError", "LinearSolver", "Linearisation", "Natural", "NewtonSettings", "NewtonSolution", "Orbit",
    "Outcome", "PeriodicQR", "PeriodicQRResult", "PointRecord", "PseudoArclength", "SPARSE_MIN_N", "SPECIAL_TYPES",
    "Scheme", "SparseSweep", "SpecialPoint", "TransferProduct", "adjoint_gradient", "analyse", "batched_newton",
    "bind_solver", "color_pattern", "continue_cycles", "continue_equilibria", "correct_cycle", "dense_jacobian", "dense_newton_step",
    "functional_derivatives", "hopf_point", "jacobian_values", "leading_multiplier", "locate",
    "multiplier_derivatives", "multiplier_gradient", "multipliers_periodic", "multipliers_product",
    "natural_constraint", "newton_solve", "newton_solve_host", "nontrivial", "orbit_from_function",
    "orbit_from_samples", "orbit_sensitivities", "palc_constraint", "start_from_branch", "start_from_function",
    "start_from_hopf", "start_from_pd", "start_from_samples", "transfer_matrices", "trivial_error", "uniform_mesh",
]
