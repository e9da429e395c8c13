"""The closed loop's Drake LeafSystems, one per module (docs/concepts/closed-loop.md)."""
