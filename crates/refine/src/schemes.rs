//! Uniform schemes: the (2m+2)-point n-ary family and natural cubic subdivision.
