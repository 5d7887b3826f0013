"""Domains: Netgen geometries with the initial cracks embedded (rectangles, boxes, CAD shapes)."""
