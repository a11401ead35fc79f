"""The uniform field: the magnetic Greenhill problem (stability of the straight rod,
its critical loads and lengths) and the buckled branch."""
