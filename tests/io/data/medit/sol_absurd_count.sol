MeshVersionFormatted 2
Dimension 3
SolAtVertices
123456789
1 1
1
End
