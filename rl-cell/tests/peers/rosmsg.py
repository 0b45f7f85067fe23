"""ROS 2 Jazzy messages from plain dicts, with PyPI rosbags' type store (shared by the peers)."""

import numpy as np
from rosbags.typesys import Stores, get_typestore

store = get_typestore(Stores.ROS2_JAZZY)


def build(typename, value):
    """The rosbags message `typename` with the field values of the nested dict `value`."""
    cls = store.types[typename]
    kwargs = {}
    for name, desc in store.fielddefs[typename][1]:
        v = value[name]
        if desc[0] == 2:  # a nested message
            kwargs[name] = build(desc[1], v)
        elif desc[0] in (3, 4):  # an array or a sequence
            sub_kind, sub = desc[1][0]
            if sub_kind == 2:
                kwargs[name] = [build(sub, x) for x in v]
            elif sub[0] == 'string':
                kwargs[name] = list(v)
            else:
                kwargs[name] = np.array(v, dtype=np.float64)
        else:
            kwargs[name] = v
    return cls(**kwargs)
