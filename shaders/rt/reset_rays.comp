#version 460
// The compacted ray list's indirect arguments before classification: (0, 1, 1).
layout(local_size_x = 1) in;
layout(set = 0, binding = 0, std430) buffer Args { uint args[4]; };
void main() { args[0] = 0u; args[1] = 1u; args[2] = 1u; args[3] = 0u; }
