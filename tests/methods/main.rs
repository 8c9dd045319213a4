//! Tests of the lighting methods, one module per method or scene family, against closed forms,
//! the path tracer or brute-force quadrature. One binary so the library is linked once.

#[path = "../support/mod.rs"]
mod support;

mod assets;
mod bsp_lights;
mod budget;
mod bush_mesh;
mod clustered;
mod combinations;
mod cube_environment;
mod environment_input;
mod forward_translucency;
mod heightfield;
mod heightfield_environment;
mod heightfield_measure;
mod heightfield_textures;
mod light_board;
mod lpv;
mod many_lights_agree;
mod prt_frame;
mod prt_raster;
mod prt_rays;
mod prt_scenes;
mod radiosity;
mod radiosity_gpu;
mod seed000_frame;
mod sh_lightmap_frame;
mod sh_lightmap_gpu;
mod sh_lightmap_measure;
mod sh_lightmap_pvs;
mod sh_lightmap_vq;
mod shadow_volumes;
mod shadow_volumes_shading;
mod shadow_volumes_translucency;
mod shadow_volumes_world;
mod vls;
mod wind;
