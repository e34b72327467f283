//! GPU struct layouts shared with WGSL (`shaders/common/types.wgsl`).
