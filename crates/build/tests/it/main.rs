//! The crate's integration tests as one binary (linked once instead of once per file:
//! issue 36, the test suite's build time); each file is a module.

mod bdpt_record;
mod beer_media;
mod bidirectional;
mod camera_depth;
mod chi2_lights;
mod cutout;
mod declared_spectra;
mod dispersion_render;
mod ellipsoid;
mod equal_area_envmap;
mod furnace_media;
mod furnace_render;
mod instancing;
mod light_selection;
mod media_emission;
mod mip_filtering;
mod mitsuba_bsdfs;
mod mitsuba_emitters;
mod mitsuba_legacy;
mod motion_blur;
mod nori;
mod nori_vdb_box;
mod normal_map;
mod null_path;
mod path_variants;
mod pbrt_grid_media;
mod pbrt_image_lights;
mod pbrt_references;
mod photon_density;
mod photon_emission;
mod references;
mod render_seeds;
mod repo_references;
mod sppm;
mod volpath_record;
