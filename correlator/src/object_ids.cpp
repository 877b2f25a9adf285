#include "ugv/correlator/object_ids.hpp"

namespace ugv::correlator {

ObjectIds::Issued ObjectIds::issue(bool isStatic, int index)
{
    Issued issued;
    issued.id = "ooi-" + std::to_string(next_++);
    issued.order = next_;
    index_[issued.id] = Ref{isStatic, index};
    return issued;
}

void ObjectIds::erase(const std::string& id)
{
    index_.erase(id);
}

void ObjectIds::merge(const std::string& gone, const std::string& kept)
{
    mergedInto_[gone] = kept;
}

void ObjectIds::unmerge(const std::string& id)
{
    mergedInto_.erase(id);
}

std::optional<ObjectIds::Ref> ObjectIds::find(const std::string& id) const
{
    std::string current = id;
    for (auto it = mergedInto_.find(current); it != mergedInto_.end(); it = mergedInto_.find(current)) {
        current = it->second;
    }
    const auto found = index_.find(current);
    if (found == index_.end()) {
        return std::nullopt;
    }
    return found->second;
}

} // namespace ugv::correlator
