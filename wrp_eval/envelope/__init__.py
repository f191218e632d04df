"""The wind envelope of a planned mission: P(meets spec) against U10 and the wind's direction relative to the
ship, the boundary speed per direction, and the go / no-go at the forecast (README.md)."""
