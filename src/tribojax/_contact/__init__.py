"""Contact of rough surfaces: materials, fractal surfaces, single asperities, the contact model."""
