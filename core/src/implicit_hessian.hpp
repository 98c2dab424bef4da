// The projected Hessian of the implicit step's objective (implicit_reference.hpp), as an Eigen sparse matrix: kept out
// of the public header so that code including drape's headers does not compile Eigen's sparse module.
#pragma once

#include <Eigen/SparseCore>

#include "drape/implicit_reference.hpp"

namespace drape {

/// The projected (positive semi-definite in the elastic part, positive definite with the inertia term) Hessian of G at
/// x over all 3 * particle_count coordinates, interleaved like x: inertia and drag (m/h^2 + m kr/h) I3 on the
/// diagonal; per spring the block k [max(0, 1 - l/L) (I - u u^T) + u u^T] + (kd/h) n n^T on (a,a) and (b,b), minus it
/// on (a,b) and (b,a); bending (1 + beta/h) Q (x) I3. Rows and columns of fixed particles are the identity. When every
/// spring is at or beyond its rest length it is the exact Hessian. Throws InvalidInput like implicit_objective.
Eigen::SparseMatrix<double> implicit_hessian(const ImplicitProblem& problem, std::span<const double> x);

} // namespace drape
