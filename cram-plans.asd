;;;; cram-plans: one system per layer; `cram-plans' loads them all.
;;;; Each layer's files are listed in its own DEFSYSTEM form below.

(defsystem "cram-utilities"
  :description "Lazy lists, variable bindings and small utilities (package CUT)."
  :depends-on ("alexandria")
  :pathname "prolog/"
  :serial t
  :components ((:file "utilities-package")
               (:file "lazy")
               (:file "bindings")))

(defsystem "cram-prolog"
  :description "The CRAM-dialect Prolog engine, compiled to Lisp closures (package PROLOG)."
  :depends-on ("cram-utilities" "alexandria")
  :pathname "prolog/"
  :serial t
  :components ((:file "prolog-package")))

(defsystem "cl-transforms"
  :description "3D vectors, quaternions, poses, transforms, stamped poses, a TF buffer (CL-TRANSFORMS, CL-TRANSFORMS-STAMPED, CL-TF, CRAM-TF)."
  :depends-on ("alexandria")
  :pathname "src/transforms/"
  :serial t
  :components ((:file "package")))

(defsystem "cram-native"
  :description "CFFI binding of the C shim libcram_native.so (Bullet, urdfdom, assimp, KDL, FCL, OSMesa, libpng)."
  :depends-on ("cffi" "alexandria")
  :pathname "projection/"
  :serial t
  :components ((:file "native")))

(defsystem "cram-plans"
  :description "CRAM plans with a Bullet belief state for projection: all layers."
  :version "0.1.0"
  :depends-on ("cram-utilities" "cram-prolog" "cl-transforms" "cram-native"))

;;; Tests: one system per layer, all run by cram-plans-tests.

(defsystem "cram-plans-tests/base"
  :depends-on ("fiveam")
  :pathname "tests/"
  :components ((:file "suite")))

(defsystem "cram-plans-tests/utilities"
  :depends-on ("cram-plans-tests/base" "cram-utilities")
  :pathname "tests/"
  :components ((:file "utilities-tests")))

(defsystem "cram-plans-tests/prolog"
  :depends-on ("cram-plans-tests/base" "cram-prolog")
  :pathname "tests/"
  :serial t
  :components ())

(defsystem "cram-plans-tests/transforms"
  :depends-on ("cram-plans-tests/base" "cl-transforms")
  :pathname "tests/"
  :serial t
  :components ())

(defsystem "cram-plans-tests/native"
  :depends-on ("cram-plans-tests/base" "cram-native")
  :pathname "tests/"
  :serial t
  :components ())

(defsystem "cram-plans-tests"
  :description "Every FiveAM suite of cram-plans, under the suite CRAM-PLANS-TESTS:ALL."
  :depends-on ("cram-plans-tests/utilities" "cram-plans-tests/prolog"
               "cram-plans-tests/transforms" "cram-plans-tests/native"))
