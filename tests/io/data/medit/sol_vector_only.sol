MeshVersionFormatted 2
Dimension 3
SolAtVertices
1
1 2
1 2 3
End
