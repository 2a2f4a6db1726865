//! Reading and writing images (EXR, PNG, PFM, HDR), atomically. TO BE WRITTEN (helper: sampling/film).
