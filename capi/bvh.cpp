// The C ABI: the user-box BVH and its sphere, capsule and box queries.
#include "front_end.h"

using namespace minkq::capi;

namespace {

// New boxes for a bvh, validated: `verb` names the call in messages.
minkq::Strided checked_new_boxes(const minkq_bvh* bvh, minkq_buffer boxes, const char* verb) {
  require(bvh != nullptr, Status::kInvalidArgument, "bvh is NULL");
  const minkq::Strided values = checked_buffer(bvh->device, boxes, 24, "boxes");
  require(size_t(values.count) == bvh->box_count, Status::kInvalidArgument,
          std::string(verb) + " with " + std::to_string(values.count) + " boxes but the bvh has " +
              std::to_string(bvh->box_count));
  require_finite(*bvh->device->backend, values, 6, "box");
  require_ordered_boxes(*bvh->device->backend, values);
  return values;
}

}  // namespace

extern "C" {

minkq_status minkq_bvh_create(minkq_device* device, minkq_buffer boxes, minkq_bvh** out_bvh) {
  return guarded([&] {
    require(out_bvh != nullptr, Status::kInvalidArgument, "out_bvh is NULL");
    *out_bvh = nullptr;
    require(device != nullptr, Status::kInvalidArgument, "device is NULL");
    const minkq::Strided values = checked_buffer(device, boxes, 24, "boxes");
    require_tree_size(size_t(values.count), "boxes.count");
    require_finite(*device->backend, values, 6, "box");
    require_ordered_boxes(*device->backend, values);
    auto bvh = std::make_unique<minkq_bvh>();
    bvh->device = device;
    bvh->box_count = size_t(values.count);
    bvh->store = device->backend->create_box_store(values);
    *out_bvh = bvh.release();
  });
}

void minkq_bvh_release(minkq_bvh* bvh) { delete bvh; }

minkq_status minkq_bvh_refit(minkq_bvh* bvh, minkq_buffer boxes) {
  return guarded([&] {
    const minkq::Strided values = checked_new_boxes(bvh, boxes, "refit");  // checks bvh first
    bvh->store->refit(values);
  });
}

minkq_status minkq_bvh_rebuild(minkq_bvh* bvh, minkq_buffer boxes) {
  return guarded([&] {
    const minkq::Strided values = checked_new_boxes(bvh, boxes, "rebuild");  // checks bvh first
    bvh->store->rebuild(values);
  });
}

minkq_status minkq_bvh_tree_growth(const minkq_bvh* bvh, double* out_growth) {
  return guarded([&] {
    require(bvh != nullptr, Status::kInvalidArgument, "bvh is NULL");
    require(out_growth != nullptr, Status::kInvalidArgument, "out_growth is NULL");
    *out_growth = bvh->store->tree_growth();
  });
}

minkq_status minkq_bvh_query(minkq_bvh* bvh, const minkq_bvh_query_desc* query, int32_t* out_pairs, size_t capacity,
                             minkq_memory out_memory, minkq_query_info* info) {
  return guarded([&] {
    require(bvh != nullptr, Status::kInvalidArgument, "bvh is NULL");
    require(query != nullptr, Status::kInvalidArgument, "query is NULL");
    const int64_t shape = enum_value(query->shape), mode = enum_value(query->mode);
    require(shape >= MINKQ_SHAPE_SPHERE && shape <= MINKQ_SHAPE_BOX, Status::kInvalidArgument,
            "query->shape is not a minkq_shape value");
    require(mode >= MINKQ_MODE_BOX && mode <= MINKQ_MODE_CAPSULE_EXACT, Status::kInvalidArgument,
            "query->mode is not a minkq_mode value");
    require((query->flags & ~kKnownQueryFlags) == 0, Status::kInvalidArgument, "query->flags has unknown bits");
    require(!(query->flags & MINKQ_QUERY_LEAF_EXACT), Status::kInvalidArgument,
            "MINKQ_QUERY_LEAF_EXACT applies to mesh scenes only: a bvh's leaves are boxes");
    require(query->shape != MINKQ_SHAPE_CAPSULE || query->mode != MINKQ_MODE_SPHERE, Status::kInvalidArgument,
            "sphere mode needs point queries; use capsule_ray or capsule_exact for capsules");
    require(query->shape != MINKQ_SHAPE_BOX || query->mode == MINKQ_MODE_BOX, Status::kInvalidArgument,
            "box queries support only MINKQ_MODE_BOX");
    require_count_alone(query->flags, "query");
    require_radius(query->radius);
    require(query->shape != MINKQ_SHAPE_BOX || query->radius == 0.0f, Status::kInvalidArgument,
            "box queries take radius 0 (radius " + format_float(query->radius) + "): grow the query boxes instead");
    minkq_device* device = bvh->device;
    const minkq::Strided first = checked_buffer(device, query->first, 12, "first");
    const minkq::Strided second = checked_buffer(device, query->second, 12, "second");
    const bool spheres = query->shape == MINKQ_SHAPE_SPHERE;
    require(spheres ? second.count == 0 : second.count == first.count, Status::kInvalidArgument,
            spheres ? "second must be empty for sphere queries"
                    : "second.count " + std::to_string(second.count) + " differs from first.count " +
                          std::to_string(first.count));
    require_finite(*device->backend, first, 3, "query point");
    require_finite(*device->backend, second, 3, "query point");
    const minkq::QueryKind kind = spheres ? minkq::QueryKind::kUserSpheres
                                          : (query->shape == MINKQ_SHAPE_CAPSULE ? minkq::QueryKind::kUserCapsules
                                                                                 : minkq::QueryKind::kUserBoxes);
    const minkq::QueryRequest request{kind, static_cast<minkq::Mode>(query->mode), 0u, query->radius, first, second};
    run_and_report(device, *bvh->store, request, query->flags, out_pairs, capacity, out_memory, info);
  });
}

}  // extern "C"
