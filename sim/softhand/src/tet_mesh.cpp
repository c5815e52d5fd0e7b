#include "haptic/softhand/tet_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

namespace haptic::softhand {

double signedVolume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

namespace {

void requireAxis(const std::vector<double>& axis, const char* name) {
    if (axis.size() < 2) {
        throw std::invalid_argument(std::string("makeGridMesh: axis ") + name +
                                    " needs at least 2 coordinates");
    }
    for (std::size_t i = 1; i < axis.size(); ++i) {
        if (!(axis[i] > axis[i - 1])) {
            throw std::invalid_argument(std::string("makeGridMesh: axis ") + name +
                                        " coordinates must be strictly increasing");
        }
    }
}

}  // namespace

TetMesh makeGridMesh(const std::vector<double>& xs_m, const std::vector<double>& ys_m,
                     const std::vector<double>& zs_m) {
    requireAxis(xs_m, "x");
    requireAxis(ys_m, "y");
    requireAxis(zs_m, "z");
    const int nx = static_cast<int>(xs_m.size());
    const int ny = static_cast<int>(ys_m.size());
    const int nz = static_cast<int>(zs_m.size());
    TetMesh mesh;
    mesh.nodes_m.reserve(static_cast<std::size_t>(nx * ny * nz));
    for (int k = 0; k < nz; ++k) {
        for (int j = 0; j < ny; ++j) {
            for (int i = 0; i < nx; ++i) {
                mesh.nodes_m.emplace_back(xs_m[i], ys_m[j], zs_m[k]);
            }
        }
    }
    const auto id = [&](int i, int j, int k) { return i + nx * (j + ny * k); };
    // Kuhn split: the 6 monotone paths from corner 000 to 111, one tetrahedron each.
    static constexpr std::array<std::array<int, 3>, 6> kAxisOrders{
        {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
    mesh.tets.reserve(static_cast<std::size_t>(6 * (nx - 1) * (ny - 1) * (nz - 1)));
    for (int k = 0; k + 1 < nz; ++k) {
        for (int j = 0; j + 1 < ny; ++j) {
            for (int i = 0; i + 1 < nx; ++i) {
                for (const auto& order : kAxisOrders) {
                    std::array<int, 3> corner{i, j, k};
                    std::array<int, 4> tet{};
                    tet[0] = id(corner[0], corner[1], corner[2]);
                    for (int step = 0; step < 3; ++step) {
                        ++corner[order[step]];
                        tet[step + 1] = id(corner[0], corner[1], corner[2]);
                    }
                    const auto& p = mesh.nodes_m;
                    if (signedVolume(p[tet[0]], p[tet[1]], p[tet[2]], p[tet[3]]) < 0.0) {
                        std::swap(tet[2], tet[3]);
                    }
                    mesh.tets.push_back(tet);
                }
            }
        }
    }
    return mesh;
}

TetMesh makeBoxMesh(const Vec3& lo_m, const Vec3& hi_m, std::array<int, 3> cells) {
    std::array<std::vector<double>, 3> axes;
    for (int a = 0; a < 3; ++a) {
        if (cells[a] < 1) {
            throw std::invalid_argument("makeBoxMesh: at least one cell per axis");
        }
        axes[a] = gradedCoordinates(lo_m[a], hi_m[a], cells[a], 1.0);
    }
    return makeGridMesh(axes[0], axes[1], axes[2]);
}

std::vector<double> gradedCoordinates(double a_m, double b_m, int count, double ratio) {
    if (count < 1 || !(ratio > 0.0)) {
        throw std::invalid_argument("gradedCoordinates: count >= 1 and ratio > 0 required");
    }
    std::vector<double> weights(static_cast<std::size_t>(count));
    double total = 0.0;
    for (int i = 0; i < count; ++i) {
        weights[i] = std::pow(ratio, i);
        total += weights[i];
    }
    std::vector<double> out{a_m};
    double acc = 0.0;
    for (int i = 0; i < count; ++i) {
        acc += weights[i];
        out.push_back(a_m + (b_m - a_m) * acc / total);
    }
    out.back() = b_m;
    return out;
}

TetMesh carveMesh(const TetMesh& mesh, const std::function<bool(const Vec3&)>& inside) {
    std::vector<int> remap(mesh.nodes_m.size(), -1);
    TetMesh out;
    for (const auto& tet : mesh.tets) {
        const Vec3 centroid = 0.25 * (mesh.nodes_m[tet[0]] + mesh.nodes_m[tet[1]] +
                                      mesh.nodes_m[tet[2]] + mesh.nodes_m[tet[3]]);
        if (!inside(centroid)) {
            continue;
        }
        std::array<int, 4> mapped{};
        for (int c = 0; c < 4; ++c) {
            int& slot = remap[tet[c]];
            if (slot < 0) {
                slot = static_cast<int>(out.nodes_m.size());
                out.nodes_m.push_back(mesh.nodes_m[tet[c]]);
            }
            mapped[c] = slot;
        }
        out.tets.push_back(mapped);
    }
    return out;
}

std::vector<int> surfaceNodes(const TetMesh& mesh) {
    std::map<std::array<int, 3>, int> face_count;
    static constexpr std::array<std::array<int, 3>, 4> kFaces{
        {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}}};
    for (const auto& tet : mesh.tets) {
        for (const auto& face : kFaces) {
            std::array<int, 3> key{tet[face[0]], tet[face[1]], tet[face[2]]};
            std::sort(key.begin(), key.end());
            ++face_count[key];
        }
    }
    std::vector<char> on_surface(mesh.nodes_m.size(), 0);
    for (const auto& [face, count] : face_count) {
        if (count == 1) {
            for (int node : face) {
                on_surface[node] = 1;
            }
        }
    }
    std::vector<int> out;
    for (std::size_t i = 0; i < on_surface.size(); ++i) {
        if (on_surface[i] != 0) {
            out.push_back(static_cast<int>(i));
        }
    }
    return out;
}

}  // namespace haptic::softhand
