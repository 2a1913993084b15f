"""DynamicPoints: unify a time series of point clouds into one deforming mesh.

Every VTK class of the toolkit is available by its VTK name::

    import dynamicpoints
    source = dynamicpoints.vtkPointSequenceSource()
    source.SetFileName("frames/points.series")

The classes are ordinary VTK algorithms: connect them to any ``vtkmodules`` pipeline.
"""
# The base classes' modules must be loaded before ours.
import vtkmodules.vtkCommonCore  # noqa: F401
import vtkmodules.vtkCommonDataModel  # noqa: F401
import vtkmodules.vtkCommonExecutionModel  # noqa: F401

from .DynamicPointsFilters import *  # noqa: F401,F403

__version__ = "0.1.0"
