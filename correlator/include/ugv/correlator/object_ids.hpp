#pragma once

/// @file
/// The ids of mode `pose-corrected`'s objects, static and mobile: issued in creation order ("ooi-N"), found by id,
/// and an id merged into another leads to the object that absorbed it (confirmations of an old id still land) until
/// a split undoes the merge.
///
/// Thread-safety: thread-bound. RT-safe: no (allocates).

#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>

namespace ugv::correlator {

class ObjectIds {
public:
    /// Where an id's object lives: the static map or the mobile tracker, and its index there.
    struct Ref {
        bool isStatic = true;
        int index = -1;
    };
    struct Issued {
        std::string id;
        std::uint64_t order = 0; ///< creation order: on a merge the lower one keeps its id
    };

    /// A new id for the object at `index` of the static map (`isStatic`) or of the mobile tracker.
    Issued issue(bool isStatic, int index);
    /// The object is gone (no merge): its id is not found any more.
    void erase(const std::string& id);
    /// `gone` was merged into `kept`: `gone` now leads to `kept`.
    void merge(const std::string& gone, const std::string& kept);
    /// A split undid the merge of `id`: it leads to its own object again.
    void unmerge(const std::string& id);
    /// The object of `id`, following merges; nullopt when unknown or erased.
    [[nodiscard]] std::optional<Ref> find(const std::string& id) const;

private:
    std::unordered_map<std::string, std::string> mergedInto_;
    std::unordered_map<std::string, Ref> index_;
    std::uint64_t next_ = 1;
};

} // namespace ugv::correlator
