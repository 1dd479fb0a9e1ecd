// Test support for every FlatBvh builder (top-down BVH, LBVH): the invariants a finished
// tree must satisfy whatever the split criterion.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "accelbench/accel/bvh/bvh_packet_leaves.h"
#include "accelbench/accel/bvh/flat_bvh.h"
#include "accelbench/scene/scene.h"

namespace accelbench::test {

inline bool contains(const Bounds3& outer, const Bounds3& inner) {
    return outer.lower.x <= inner.lower.x && outer.lower.y <= inner.lower.y && outer.lower.z <= inner.lower.z &&
        outer.upper.x >= inner.upper.x && outer.upper.y >= inner.upper.y && outer.upper.z >= inner.upper.z;
}

// Checks: each triangle in exactly one leaf slot; leaves cover the slots in order;
// depth-first layout (first child follows its parent, second child after the first
// child's subtree); every box contains its children's or its triangles' boxes, and with
// `tight` equals their union; the leaf triangle copies match the scene (with `copies`; a
// tree whose leaves are packets has released them: see expect_valid_packets); depth is right.
inline void expect_valid_bvh(const FlatBvh& bvh, const Scene& scene, bool tight, const std::string& what,
                             bool copies = true) {
    const size_t n = scene.triangle_count();
    if (n == 0) {
        EXPECT_TRUE(bvh.nodes.empty()) << what;
        return;
    }
    ASSERT_FALSE(bvh.nodes.empty()) << what;
    ASSERT_EQ(bvh.prim_ids.size(), n) << what;
    ASSERT_EQ(bvh.triangles.size(), copies ? n : 0) << what;
    std::vector<int> seen(n, 0);
    for (size_t slot = 0; slot < n; ++slot) {
        ASSERT_LT(bvh.prim_ids[slot], n) << what;
        ++seen[bvh.prim_ids[slot]];
        if (!copies) continue;
        const uint32_t p = bvh.prim_ids[slot];
        EXPECT_EQ(bvh.triangles[slot].p0, scene.vertex(p, 0)) << what;
        EXPECT_EQ(bvh.triangles[slot].p1, scene.vertex(p, 1)) << what;
        EXPECT_EQ(bvh.triangles[slot].p2, scene.vertex(p, 2)) << what;
    }
    for (size_t i = 0; i < n; ++i) EXPECT_EQ(seen[i], 1) << what << ": triangle " << i;

    // Walk the tree depth-first: node indices must come in order 0, 1, 2, ... and leaf
    // slots in order 0, 1, 2, ...
    struct Item {
        uint32_t node, depth;
    };
    std::vector<Item> stack{{0, 0}};
    uint32_t expected_node = 0, next_slot = 0, depth = 0;
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        ASSERT_EQ(it.node, expected_node) << what << ": not depth-first";
        ++expected_node;
        depth = std::max(depth, it.depth);
        const BvhNode& node = bvh.nodes[it.node];
        Bounds3 content;
        if (node.is_leaf()) {
            ASSERT_EQ(node.first_prim(), next_slot) << what;
            next_slot += node.prim_count();
            ASSERT_LE(next_slot, n) << what;
            for (uint32_t s = node.first_prim(); s < next_slot; ++s) content.extend(scene.prim_bounds[bvh.prim_ids[s]]);
        } else {
            ASSERT_LT(node.second_child(), bvh.nodes.size()) << what;
            content = merge(bvh.nodes[it.node + 1].bounds, bvh.nodes[node.second_child()].bounds);
            stack.push_back({node.second_child(), it.depth + 1});
            stack.push_back({it.node + 1, it.depth + 1});
        }
        EXPECT_TRUE(contains(node.bounds, content)) << what << ": node " << it.node;
        if (tight) {
            EXPECT_EQ(node.bounds, content) << what << ": node " << it.node;
        }
    }
    EXPECT_EQ(expected_node, bvh.nodes.size()) << what << ": unreachable nodes";
    EXPECT_EQ(next_slot, n) << what;
    EXPECT_EQ(bvh.depth, depth) << what;
}

// Lane `lane` of packet `p` (wbvh_simd.h: the wide BVH's leaves and the binary BVH's packet
// leaves) holds the scene's triangle `prim`: its three vertices, bit for bit.
inline void expect_lane_holds(const WbvhTriPacket& p, int lane, uint32_t prim, const Scene& scene,
                              const std::string& what) {
    for (int v = 0; v < 3; ++v)
        EXPECT_EQ((Vec3{p.v[v][0][lane], p.v[v][1][lane], p.v[v][2][lane]}), scene.vertex(prim, v))
            << what << ": triangle " << prim << " vertex " << v;
}

// The packets of a tree's leaves (bvh_packet_leaves.h): each leaf's slots in order, four to
// a packet, every lane holding its slot's scene triangle and index, the lanes past the
// leaf's count empty (kInvalidId).
inline void expect_valid_packets(const BvhPacketLeaves& leaves, const FlatBvh& bvh, const Scene& scene,
                                 const std::string& what) {
    ASSERT_EQ(leaves.first_packet.size(), bvh.nodes.size()) << what;
    size_t expected_first = 0;
    for (size_t i = 0; i < bvh.nodes.size(); ++i) {
        const BvhNode& node = bvh.nodes[i];
        if (!node.is_leaf()) continue;
        ASSERT_EQ(leaves.first_packet[i], expected_first) << what << ": node " << i;
        const uint32_t count = node.prim_count();
        const size_t packets = (count + WbvhTriPacket::kLanes - 1) / WbvhTriPacket::kLanes;
        ASSERT_LE(expected_first + packets, leaves.packets.size()) << what << ": node " << i;
        for (uint32_t k = 0; k < packets * WbvhTriPacket::kLanes; ++k) {
            const WbvhTriPacket& p = leaves.packets[expected_first + k / WbvhTriPacket::kLanes];
            const int lane = int(k % WbvhTriPacket::kLanes);
            if (k >= count) {
                EXPECT_EQ(p.prim[lane], kInvalidId) << what << ": node " << i << " lane " << lane;
                continue;
            }
            const uint32_t prim = bvh.prim_ids[node.first_prim() + k];
            ASSERT_EQ(p.prim[lane], prim) << what << ": node " << i << " slot " << k;
            expect_lane_holds(p, lane, prim, scene, what + ": node " + std::to_string(i));
        }
        expected_first += packets;
    }
    EXPECT_EQ(expected_first, leaves.packets.size()) << what;
}

}  // namespace accelbench::test
