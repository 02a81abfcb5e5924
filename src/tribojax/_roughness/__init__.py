"""Surface roughness: synthesis of fractal surfaces, measured topographies, D and G estimates."""
