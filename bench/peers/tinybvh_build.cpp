// Peer for `lenspath bench bvh`: times tinybvh's SAH builders (BVH::Build, the
// scalar reference, and BVH::BuildAVX) on the same triangles, and its build of
// the 8-wide CPU layout (BVH8_CPU::Build). Single-threaded unless compiled with
// -DPEER_THREADED (tinybvh's own threaded builds, on every core).
// Reads the binary PLY written by `lenspath bench bvh --save-mesh`.
// Usage: tinybvh_build MESH.ply C_INT ROUNDS  -> one JSON line per builder.
#ifndef PEER_THREADED
#define NO_THREADED_BUILDS
#endif
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

// Only the layout lenspath writes: float x y z vertices, uchar-counted int faces.
static std::vector<tinybvh::bvhvec4> read_triangles(const char* path) {
    FILE* f = fopen(path, "rb");
    if (!f) { fprintf(stderr, "%s: cannot open\n", path); exit(2); }
    char line[256];
    long vertices = -1, faces = -1;
    while (fgets(line, sizeof line, f) && strcmp(line, "end_header\n") != 0) {
        sscanf(line, "element vertex %ld", &vertices);
        sscanf(line, "element face %ld", &faces);
    }
    if (vertices < 0 || faces < 0) { fprintf(stderr, "%s: not a lenspath PLY\n", path); exit(2); }
    std::vector<float> xyz(3 * vertices);
    if (fread(xyz.data(), 4, xyz.size(), f) != xyz.size()) { fprintf(stderr, "%s: short read\n", path); exit(2); }
    std::vector<tinybvh::bvhvec4> soup;
    soup.reserve(3 * faces);
    for (long i = 0; i < faces; i++) {
        unsigned char n;
        int v[3];
        if (fread(&n, 1, 1, f) != 1 || n != 3 || fread(v, 4, 3, f) != 3) {
            fprintf(stderr, "%s: face %ld is not a triangle\n", path, i);
            exit(2);
        }
        for (int k = 0; k < 3; k++) soup.emplace_back(xyz[3 * v[k]], xyz[3 * v[k] + 1], xyz[3 * v[k] + 2], 0.0f);
    }
    fclose(f);
    return soup;
}

int main(int argc, char** argv) {
    if (argc != 4) { fprintf(stderr, "usage: %s MESH.ply C_INT ROUNDS\n", argv[0]); return 2; }
    std::vector<tinybvh::bvhvec4> soup = read_triangles(argv[1]);
    const uint32_t triangles = (uint32_t)(soup.size() / 3);
    const float c_int = (float)atof(argv[2]);
    const int rounds = atoi(argv[3]);
    // Build and BuildAVX make tinybvh's binary tree; BVH8_CPU::Build makes its
    // fastest CPU layout from BuildAVX's tree (8-wide nodes, 4-triangle
    // leaves: what lenspath's build returns), so it adds the conversion.
    for (const std::string builder : {"Build", "BuildAVX", "BVH8_CPU::Build"}) {
        std::vector<double> ms;
        uint32_t nodes = 0;
        for (int r = 0; r < rounds; r++) {
            if (builder == "BVH8_CPU::Build") {
                tinybvh::BVH8_CPU bvh8;
                bvh8.bvh8.bvh.c_int = c_int;
                bvh8.bvh8.bvh.c_trav = 1.0f;
                auto t0 = std::chrono::steady_clock::now();
                bvh8.Build(soup.data(), triangles);
                ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
                nodes = bvh8.bvh8.bvh.usedNodes;
                continue;
            }
            tinybvh::BVH bvh;
            bvh.c_int = c_int;
            bvh.c_trav = 1.0f;
            auto t0 = std::chrono::steady_clock::now();
            if (builder == "Build") bvh.Build(soup.data(), triangles); else bvh.BuildAVX(soup.data(), triangles);
            ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
            nodes = bvh.usedNodes;
        }
        std::sort(ms.begin(), ms.end());
        printf("{\"builder\": \"tinybvh %s\", \"triangles\": %u, \"intersection_cost\": %g, \"nodes\": %u, "
               "\"build_ms_min\": %.1f, \"build_ms_median\": %.1f}\n",
               builder.c_str(), triangles, c_int, nodes, ms.front(), ms[ms.size() / 2]);
    }
    return 0;
}
