//! Ray–primitive intersection and the BVH. TO BE WRITTEN (helper: accel).
