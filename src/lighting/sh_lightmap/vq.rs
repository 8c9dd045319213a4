//! Vector quantisation of SH transfer vectors (seed 000 §5.6).
