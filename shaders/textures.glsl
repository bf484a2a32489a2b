// textures.glsl — material textures: one array, every image resampled to a common size on the host
// (a sampler array could not be indexed per pixel in GLSL 4.50). Repeat, bilinear, no mipmaps.
uniform sampler2DArray u_textures;
