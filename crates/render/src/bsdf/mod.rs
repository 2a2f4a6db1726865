//! BSDF models in the local shading frame. TO BE WRITTEN (helper: bsdf).
