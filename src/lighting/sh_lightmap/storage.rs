//! Storage of SH light-maps: range-encoded RGBA8 layers, float layers, VQ tables and index maps.
