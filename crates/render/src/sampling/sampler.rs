//! Per-pixel sample generators. TO BE WRITTEN (helper: sampling/film).
