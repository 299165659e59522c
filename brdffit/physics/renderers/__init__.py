"""The renderers' own models, evaluated in JAX exactly as the renderer does."""
