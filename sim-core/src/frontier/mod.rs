//! Frontier detection and goal blacklisting.
