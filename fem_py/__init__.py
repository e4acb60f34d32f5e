"""DOLFINx side of the coupling: geometry, materials, expressions, interior forms, boundary map."""
