;;;; Package CRAM-MATH (nickname CMA): double-float matrices, sampling from distributions,
;;;; the multivariate Gaussian, points in polygons.

(defpackage :cram-math
  (:nicknames :cma)
  (:use :cl)
  (:export
   ;; sampling
   #:sample #:sample-discrete #:invalid-probability-distribution
   #:sample-from-distribution-matrix #:*random-state-of-sampling* #:seed-sampling
   ;; matrices
   #:double-matrix #:width #:height #:make-double-matrix #:make-double-vector
   #:double-vector-size #:fill-double-matrix #:double-matrix-from-array
   #:double-matrix-from-grid #:grid-from-double-matrix #:mref #:map-double-matrix
   #:map-double-matrix-into #:double-matrix-transpose #:double-matrix-product
   #:m.+ #:m.- #:m.* #:m./ #:m+ #:m- #:m* #:m/
   ;; functions
   #:determinant #:invert-matrix #:gauss
   ;; geometry
   #:2d-point #:x #:y #:polygon #:vertices #:point-in-polygon
   #:degrees->radians #:radians->degrees))
