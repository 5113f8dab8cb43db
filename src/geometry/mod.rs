//! Obstacles and containers on parry3d: shapes, meshes, signed distance, rigid motion, surface sampling.
