//! The ray-cast truth (placeholder; being written).
