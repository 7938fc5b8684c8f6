#pragma once
// OpenGL 4.5 core prototypes through glvnd (libOpenGL), so that one binary runs on Mesa and on
// NVIDIA's EGL.

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
