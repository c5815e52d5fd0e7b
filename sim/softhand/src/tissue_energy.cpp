#include <algorithm>
#include <array>

#include "energy_terms.hpp"

namespace haptic::softhand {

void addLinearizedTerm(Assembler* assembler, const Vec3& gradient, const Mat3& hessian,
                       std::span<const JacobianBlock> blocks) {
    if (assembler == nullptr) {
        return;
    }
    for (const auto& bi : blocks) {
        assembler->addGradient(bi.dof, bi.jacobian.transpose() * gradient);
        const Eigen::Matrix3d left = bi.jacobian.transpose() * hessian;
        for (const auto& bj : blocks) {
            assembler->addBlock(bi.dof, bj.dof, left * bj.jacobian);
        }
    }
}

double addResidualTerm(Assembler* assembler, const Mat3& weight, const Vec3& residual,
                       std::span<const JacobianBlock> blocks) {
    const Vec3 weighted = weight * residual;
    addLinearizedTerm(assembler, weighted, weight, blocks);
    return 0.5 * residual.dot(weighted);
}

double EnergyTerms::tissue(const Sim& sim, const Sim::Configuration& q, Assembler* assembler,
                           TermStats* stats) {
    if (assembler != nullptr) {
        assembler->collecting_tissue = assembler->keepsTissuePart();
    }
    double energy = 0.0;
    for (std::size_t e = 0; e < sim.tets_.size(); ++e) {
        const auto& tet = sim.tets_[e];
        const auto& n = tet.nodes;
        Mat3 ds;
        ds.col(0) = q.x[n[1]] - q.x[n[0]];
        ds.col(1) = q.x[n[2]] - q.x[n[0]];
        ds.col(2) = q.x[n[3]] - q.x[n[0]];
        const Mat3 f = ds * tet.rest_inverse;
        // Most elements are well inside the strain limits: the polar rotation alone gives
        // the energy, and since |sigma_i - 1| <= |R^T F - I|_F the limits cannot be active
        // below that margin. Elements near a limit, flat or inverted take the full SVD.
        Mat3 rotation;
        const bool polar = polarRotation(f, rotation);
        Mat3 strain = polar ? Mat3(rotation.transpose() * f - Mat3::Identity()) : Mat3::Zero();
        const double margin = std::min(tet.strain_max - 1.0, 1.0 - tet.strain_min);
        const bool need_svd = !polar || (tet.strain_limits && !(strain.norm() < margin));
        RotationVariantSvd svd{Mat3::Identity(), Vec3::Ones(), Mat3::Identity()};
        if (need_svd) {
            svd = rotationVariantSvd(f);
            rotation = svd.rotation();
            strain = rotation.transpose() * f - Mat3::Identity();
        }
        const double trace = strain.trace();
        energy += tet.volume_m3 *
                  (tet.mu * (f - rotation).squaredNorm() + 0.5 * tet.lambda * trace * trace);

        // Shape-function gradients g_j: rows of D_m^-1, g_0 = -(g_1 + g_2 + g_3).
        std::array<Vec3, 4> g;
        g[1] = tet.rest_inverse.row(0).transpose();
        g[2] = tet.rest_inverse.row(1).transpose();
        g[3] = tet.rest_inverse.row(2).transpose();
        g[0] = -(g[1] + g[2] + g[3]);

        // Strain-limit penalty on the singular values (inversion-safe: sigma_3 < 0 when
        // inverted, which is far below strain_min, so the penalty restores orientation).
        Vec3 excess = Vec3::Zero();
        bool limited = false;
        if (tet.strain_limits && need_svd) {
            for (int i = 0; i < 3; ++i) {
                const double s = svd.sigma(i);
                if (s > tet.strain_max) {
                    excess(i) = s - tet.strain_max;
                } else if (s < tet.strain_min) {
                    excess(i) = s - tet.strain_min;
                }
                limited = limited || excess(i) != 0.0;
            }
            energy += 0.5 * tet.limit_stiffness * tet.volume_m3 * excess.squaredNorm();
        }
        if (stats != nullptr) {
            stats->strain_limited_elements += limited ? 1 : 0;
            stats->inverted_elements += need_svd && svd.sigma(2) < 0.0 ? 1 : 0;
        }
        if (assembler == nullptr) {
            continue;
        }
        // First Piola stress of the co-rotational model with R frozen, plus the penalty.
        Mat3 piola = 2.0 * tet.mu * (f - rotation) + tet.lambda * trace * rotation;
        if (limited) {
            piola += svd.u * (tet.limit_stiffness * excess).asDiagonal() * svd.v.transpose();
        }
        for (int j = 0; j < 4; ++j) {
            assembler->addGradient(nodeDof(n[j]), tet.volume_m3 * piola * g[j]);
        }
        // R K_ij R^T with K_ij = mu (g_i.g_j) I + mu g_j g_i^T + lambda g_i g_j^T, written
        // with the rotated gradients R g_i so each block costs two outer products.
        std::array<Vec3, 4> rotated;
        for (int i = 0; i < 4; ++i) {
            rotated[i] = rotation * g[i];
        }
        // K_ji = K_ij^T, so the ten blocks i <= j are computed and mirrored.
        const std::array<int, 16>* slots = assembler->elementSlots(e, n);
        for (int i = 0; i < 4; ++i) {
            for (int j = i; j < 4; ++j) {
                Mat3 block = tet.volume_m3 * (tet.mu * g[i].dot(g[j]) * Mat3::Identity() +
                                              tet.mu * rotated[j] * rotated[i].transpose() +
                                              tet.lambda * rotated[i] * rotated[j].transpose());
                if (limited) {
                    for (int a = 0; a < 3; ++a) {
                        if (excess(a) == 0.0) {
                            continue;
                        }
                        const Vec3 va = svd.v.col(a);
                        const Vec3 ua = svd.u.col(a);
                        block += tet.limit_stiffness * tet.volume_m3 * va.dot(g[i]) * va.dot(g[j]) *
                                 ua * ua.transpose();
                    }
                }
                if (slots != nullptr) {
                    assembler->addBlockAt((*slots)[4 * i + j], block);
                    if (j != i) {
                        assembler->addTransposedBlockAt((*slots)[4 * j + i], block);
                    }
                } else {
                    assembler->addBlock(nodeDof(n[i]), nodeDof(n[j]), block);
                    if (j != i) {
                        assembler->addBlock(nodeDof(n[j]), nodeDof(n[i]), block.transpose());
                    }
                }
            }
        }
    }
    if (assembler != nullptr) {
        assembler->collecting_tissue = false;
    }
    return energy;
}

double EnergyTerms::external(const Sim& sim, const Sim::Configuration& q, Assembler* assembler) {
    const Vec3& gravity = sim.settings_.gravity_m_per_s2;
    double energy = 0.0;
    for (int i = 0; i < sim.nodeCount(); ++i) {
        const Vec3 load = sim.node_mass_[i] * gravity + sim.node_force_[i];
        energy -= load.dot(q.x[i]);
        if (assembler != nullptr) {
            assembler->addGradient(nodeDof(i), -load);
        }
    }
    for (int b = 0; b < sim.bodyCount(); ++b) {
        const auto& body = sim.bodies_[b];
        if (!body.gravity || body.kinematic) {
            continue;
        }
        const Vec3 load = body.mass * gravity;
        energy -= load.dot(q.c[b]);
        if (assembler != nullptr) {
            assembler->addGradient(bodyDof(sim, b), -load);
        }
    }
    return energy;
}

}  // namespace haptic::softhand
