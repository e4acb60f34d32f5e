"""The coupled functional J_h, the preconditioners, the projection and the PGPM solver."""
