"""Reading and writing: meshes in (keeping the user's vertex order), rigs out (glTF)."""
