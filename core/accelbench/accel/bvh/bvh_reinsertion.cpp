#include "accelbench/accel/bvh/bvh_reinsertion.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

namespace accelbench {

namespace {

// The tree with explicit links, which moving subtrees needs (the flat array encodes
// the topology in the node order). Node ids are the FlatBvh's indices.
class LinkedTree {
public:
    explicit LinkedTree(const FlatBvh& bvh)
        : nodes_(bvh.nodes),
          box_(bvh.nodes.size()),
          left_(bvh.nodes.size(), kInvalidId),
          right_(bvh.nodes.size(), kInvalidId),
          parent_(bvh.nodes.size(), kInvalidId) {
        for (uint32_t i = 0; i < size(); ++i) {
            box_[i] = nodes_[i].bounds;
            if (nodes_[i].is_leaf()) continue;
            left_[i] = i + 1;
            right_[i] = nodes_[i].second_child();
            parent_[i + 1] = parent_[right_[i]] = i;
        }
    }

    uint32_t size() const { return uint32_t(nodes_.size()); }
    float area(uint32_t n) const { return box_[n].area(); }
    bool is_leaf(uint32_t n) const { return left_[n] == kInvalidId; }
    uint32_t parent(uint32_t n) const { return parent_[n]; }
    uint32_t sibling(uint32_t n) const {
        const uint32_t p = parent_[n];
        return left_[p] == n ? right_[p] : left_[p];
    }

    struct Move {
        uint32_t from = kInvalidId, to = kInvalidId;
        float gain = 0.0f;  // summed inner-node area removed
    };

    // The best place for `from` (not the root): Meister & Bittner's search as bvh v2
    // writes it. Taking `from` out removes its parent's area and shrinks the ancestors
    // above; `removed` is that gain as far as the search has climbed. Going up one
    // ancestor at a time, the subtree of that ancestor's other child is searched depth
    // first: putting `from` beside node x costs area(x u from) for the new parent, and
    // below x every level pays x's growth again (`induced`). A branch is cut when even
    // area(from), the least a new parent can cost, exceeds what is left to gain.
    Move best_move(uint32_t from) {
        Move best{from, kInvalidId, 0.0f};
        const Bounds3& moved = box_[from];
        const float moved_area = area(from);
        const uint32_t parent = parent_[from];
        float removed = area(parent);
        uint32_t sibling = this->sibling(from), pivot = parent;
        Bounds3 pivot_box = box_[sibling];  // what the pivot would bound without `from`
        for (;;) {
            stack_.push_back({sibling, removed});
            while (!stack_.empty()) {
                const Candidate c = stack_.back();
                stack_.pop_back();
                if (c.budget - moved_area <= best.gain) continue;
                Bounds3 merged = box_[c.node];
                merged.extend(moved);
                const float gain = c.budget - merged.area();
                if (gain > best.gain) best = {from, c.node, gain};
                if (!is_leaf(c.node)) {
                    const float budget = gain + area(c.node);  // below c.node, c.node grows instead
                    stack_.push_back({left_[c.node], budget});
                    stack_.push_back({right_[c.node], budget});
                }
            }
            if (pivot != parent) {
                pivot_box.extend(box_[sibling]);
                removed += area(pivot) - pivot_box.area();
            }
            if (parent_[pivot] == kInvalidId) break;
            sibling = this->sibling(pivot);
            pivot = parent_[pivot];
        }
        // Beside its own sibling or its parent, `from` would stay where it is.
        if (best.to == this->sibling(from) || best.to == parent) best = {};
        return best;
    }

    // Whether `m` is still a valid move after others were applied: `to` must not have
    // ended up inside `from`'s subtree, nor next to it.
    bool applicable(const Move& m) const {
        if (parent_[m.from] == kInvalidId || m.to == parent_[m.from] || m.to == sibling(m.from)) return false;
        for (uint32_t n = m.to; n != kInvalidId; n = parent_[n])
            if (n == m.from) return false;
        return true;
    }

    // The nodes a move rewrites; a pass applies a move only if none of them was touched.
    std::array<uint32_t, 5> conflicts(const Move& m) const {
        return {m.from, m.to, sibling(m.from), parent_[m.from], parent_[m.to]};
    }

    void apply(const Move& m) {
        const uint32_t p = parent_[m.from], s = sibling(m.from), g = parent_[p];
        // Out: the sibling takes the parent's place.
        replace_child(g, p, s);
        // In: the freed parent takes the place of `to` and adopts it and `from`.
        const uint32_t tp = parent_[m.to];
        replace_child(tp, m.to, p);
        left_[p] = m.to;
        right_[p] = m.from;
        parent_[m.to] = parent_[m.from] = p;
        refit_up(p);
        if (g != kInvalidId) refit_up(g);
    }

    uint32_t root() const { return root_; }

    // Nodes (except the root) by decreasing box area: the batch a pass tries.
    std::vector<uint32_t> largest(size_t count) const {
        std::vector<uint32_t> ids;
        ids.reserve(size());
        for (uint32_t i = 0; i < size(); ++i)
            if (i != root_) ids.push_back(i);
        count = std::min(count, ids.size());
        auto larger = [this](uint32_t a, uint32_t b) { return area(a) > area(b) || (area(a) == area(b) && a < b); };
        std::nth_element(ids.begin(), ids.begin() + ptrdiff_t(count), ids.end(), larger);
        ids.resize(count);
        std::sort(ids.begin(), ids.end(), larger);
        return ids;
    }

    // Back to a depth-first FlatBvh (first child next), leaves' primitives in the new
    // leaf order. The old split axis stays with each inner node; a moved parent gets
    // the longest axis of its new box (the axis is informational, traversal ignores it).
    FlatBvh flatten(const FlatBvh& old, const std::vector<bool>& moved) const {
        FlatBvh out;
        out.nodes.reserve(size());
        out.prim_ids.reserve(old.prim_ids.size());
        std::vector<std::pair<uint32_t, uint32_t>> todo;  // (node, out index of the parent to patch)
        todo.push_back({root_, kInvalidId});
        while (!todo.empty()) {
            const auto [n, patch] = todo.back();
            todo.pop_back();
            const uint32_t index = uint32_t(out.nodes.size());
            if (patch != kInvalidId) out.nodes[patch].index = index;
            if (is_leaf(n)) {
                const BvhNode& leaf = nodes_[n];
                const uint32_t first = uint32_t(out.prim_ids.size());
                out.prim_ids.insert(out.prim_ids.end(), old.prim_ids.begin() + leaf.first_prim(),
                                    old.prim_ids.begin() + leaf.first_prim() + leaf.prim_count());
                out.nodes.push_back(BvhNode::leaf(box_[n], first, leaf.prim_count()));
                continue;
            }
            const int axis = moved[n] ? box_[n].largest_axis() : nodes_[n].axis();
            out.nodes.push_back(BvhNode::inner(box_[n], 0, axis));
            todo.push_back({right_[n], index});  // second child, patched when emitted
            todo.push_back({left_[n], kInvalidId});
        }
        return out;
    }

private:
    struct Candidate {
        uint32_t node;
        float budget;  // area still to gain when placing `from` here
    };

    void replace_child(uint32_t parent, uint32_t old_child, uint32_t new_child) {
        if (parent == kInvalidId) {
            root_ = new_child;
        } else if (left_[parent] == old_child) {
            left_[parent] = new_child;
        } else {
            right_[parent] = new_child;
        }
        parent_[new_child] = parent;
    }

    void refit_up(uint32_t n) {
        for (; n != kInvalidId; n = parent_[n]) {
            Bounds3 b = box_[left_[n]];
            b.extend(box_[right_[n]]);
            box_[n] = b;
        }
    }

    BvhNodeArray nodes_;  // the original nodes: leaves' primitive ranges, inner axes
    std::vector<Bounds3> box_;
    std::vector<uint32_t> left_, right_, parent_;
    uint32_t root_ = 0;
    std::vector<Candidate> stack_;  // best_move's search, reused
};

}  // namespace

BvhReinsertionCounts optimize_bvh_by_reinsertion(FlatBvh& bvh, const Scene& scene, const BvhReinsertionConfig& config) {
    BvhReinsertionCounts counts;
    if (bvh.nodes.size() < 3 || config.passes == 0) return counts;
    LinkedTree tree(bvh);
    const size_t batch = std::max<size_t>(1, size_t(std::ceil(double(config.batch_ratio) * double(tree.size()))));
    std::vector<bool> touched(tree.size()), moved(tree.size());
    std::vector<LinkedTree::Move> moves;
    for (uint32_t pass = 0; pass < config.passes; ++pass) {
        moves.clear();
        for (uint32_t n : tree.largest(batch)) {
            const LinkedTree::Move m = tree.best_move(n);
            if (m.to != kInvalidId && m.gain > 0.0f) moves.push_back(m);
        }
        if (moves.empty()) break;
        // Best gains first; ties by node id, so the result does not depend on the sort.
        std::sort(moves.begin(), moves.end(), [](const LinkedTree::Move& a, const LinkedTree::Move& b) {
            return a.gain > b.gain || (a.gain == b.gain && a.from < b.from);
        });
        std::fill(touched.begin(), touched.end(), false);
        for (const LinkedTree::Move& m : moves) {
            if (!tree.applicable(m)) continue;
            const auto nodes = tree.conflicts(m);
            if (std::any_of(nodes.begin(), nodes.end(), [&](uint32_t n) { return n != kInvalidId && touched[n]; }))
                continue;
            for (uint32_t n : nodes)
                if (n != kInvalidId) touched[n] = true;
            moved[tree.parent(m.from)] = true;
            tree.apply(m);
            ++counts.reinsertions;
        }
    }
    bvh = tree.flatten(bvh, moved);
    bvh.finalize(scene);
    return counts;
}

}  // namespace accelbench
