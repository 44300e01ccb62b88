;;;; cram-native: CFFI binding of libcram_native.so (see native/cram_native.h).
;;;; This file: package, library loading, error condition, argument conversion helpers.

(defpackage :cram-native
  (:use :cl)
  (:export
   ;; errors and the library
   #:native-error #:native-error-function #:native-error-code #:native-error-message
   #:with-float-traps-masked* #:*gc-release-granularity* #:keep-freed-heap-pages
   #:library-directory #:native-version #:with-scratch-vector
   #:add-package-path #:add-search-dir #:clear-search-paths #:resolve-path
   ;; worlds
   #:make-world #:destroy-world #:copy-world #:world-alive-p #:world-count
   #:world-gravity #:set-world-gravity #:step-world #:simulate #:world-object-count
   #:world-body-count #:world-objects #:with-world
   ;; objects and bodies
   #:object-kind #:remove-object #:object-pose #:set-object-pose #:object-poses
   #:set-object-poses #:object-color #:robot-link-colors #:robot-link-aabbs #:set-object-color #:object-collision-filter
   #:set-object-collision-filter #:object-aabb #:object-local-aabb #:object-active-p
   #:add-plane #:add-box #:add-sphere #:add-cylinder #:add-cone #:add-mesh #:add-convex-hull
   #:body-velocity #:set-body-velocity #:body-mass #:body-shape
   ;; articulated objects
   #:add-urdf #:robot-name #:robot-link-count #:robot-joint-count #:robot-root-link
   #:robot-link-name #:robot-joint-name #:robot-link-names #:robot-joint-names
   #:robot-link-index #:robot-joint-index #:robot-joint-info #:robot-link-parent-joint
   #:robot-link-has-body-p #:set-robot-joints #:robot-joints #:robot-joint #:robot-link-poses #:robot-link-poses-if
   #:robot-link-pose #:set-robot-self-collision
   ;; queries
   #:world-contacts #:object-contacts #:object-first-contact #:set-contact-prefilter #:closest-distance #:ignore-pair #:ray-test
   #:ray-hit-objects
   #:attach #:detach #:attachments
   ;; rendering
   #:render #:render-png #:write-png #:look-at #:visibility
   ;; inverse kinematics
   #:make-chain #:destroy-chain #:chain-joint-count #:chain-joints #:chain-limits #:chain-fk
   #:chain-ik #:chain-ik-memo-size #:chain-may-reach-p
   #:chain-reach-map #:set-chain-reach-map))

(in-package :cram-native)

(defun library-directory ()
  "Directory holding libcram_native.so (projection/native/build/ of the cram-native system)."
  (asdf:system-relative-pathname "cram-plans/cram-native" "projection/native/build/"))

(let ((lib (merge-pathnames "libcram_native.so" (library-directory))))
  (unless (probe-file lib)
    (error "~a is missing: build it with `make -C projection/native' first." lib))
  (cffi:load-foreign-library lib))

(defvar *malloc-arena-max* 2
  "How many glibc malloc arenas the process may use (mallopt M_ARENA_MAX), set when this binding
loads and when a saved image starts; NIL, or MALLOC_ARENA_MAX in the environment, keeps glibc's
choice. Plan tasks are short-lived threads that allocate native memory (Bullet worlds); by
default glibc gives a thread that finds the arenas busy a new one, up to 8 per core, and each
keeps its freed memory: a long-running image grew by about 10 MB of RSS per 1000 projections.")

(defun limit-malloc-arenas ()
  "Apply *MALLOC-ARENA-MAX* (see there); true when glibc accepted it."
  (when (and *malloc-arena-max* (not (uiop:getenv "MALLOC_ARENA_MAX"))
             (cffi:foreign-symbol-pointer "mallopt"))
    (= 1 (cffi:foreign-funcall "mallopt" :int -8 :int *malloc-arena-max* :int)))) ; -8: M_ARENA_MAX

(limit-malloc-arenas)
(pushnew 'limit-malloc-arenas sb-ext:*init-hooks*)

(defvar *gc-release-granularity* (expt 2 30)
  "The runs of free heap pages (bytes, a power of two) SBCL's garbage collector gives back to
the kernel after a collection (its gencgc_release_granularity), set when this binding loads and
when a saved image starts; shorter runs it zeroes in place, to be used again. NIL keeps SBCL's
\(32 KB). Projection allocates about 50 MB of short-lived Lisp data per household run: given back
after every collection, the pages were faulted in again by the next runs (about 6 700 page
faults and 15 ms of kernel time per run). With the default the heap keeps the pages it has used
\(the resident set stays at the most the heap held since the start, without growing past it).
Another value set in a running image takes effect with KEEP-FREED-HEAP-PAGES.")

(defun keep-freed-heap-pages ()
  "Apply *GC-RELEASE-GRANULARITY* (see there) to SBCL's collector; its value when applied, NIL
when it is not a power of two of at least 32 KB (SBCL's setting is then left as it is)."
  (let ((g *gc-release-granularity*))
    (when (and (typep g '(integer 32768)) (= 1 (logcount g)))
      (setf (sb-alien:extern-alien "gencgc_release_granularity" sb-alien:unsigned-long) g))))

(keep-freed-heap-pages)
(pushnew 'keep-freed-heap-pages sb-ext:*init-hooks*)

(defmacro with-float-traps-masked* (&body body)
  "Run BODY with every SBCL floating point trap masked (OSMesa/llvmpipe and Bullet raise
floating point exceptions inside foreign calls otherwise)."
  `(sb-int:with-float-traps-masked (:invalid :divide-by-zero :overflow :inexact :underflow)
     ,@body))

(define-condition native-error (error)
  ((function :initarg :function :reader native-error-function
             :documentation "Name of the shim function (a string) or Lisp function that failed.")
   (code :initarg :code :reader native-error-code
         :documentation "Negative status code: -1 handle, -2 argument, -3 name, -4 file,
-5 parse, -6 state, -7 render, -8 internal.")
   (message :initarg :message :reader native-error-message
            :documentation "Text naming the bad value."))
  (:report (lambda (c s)
             (format s "~a: ~a" (native-error-function c) (native-error-message c))))
  (:documentation "Signalled when a call of the native shim fails or its arguments are invalid."))

(cffi:defcfun ("cn_last_error" %last-error) :string)
(cffi:defcfun ("cn_version" %version) :int)

(defun signal-native-error (function code)
  (error 'native-error :function function :code code :message (%last-error)))

(defun arg-error (function fmt &rest args)
  "Signal a NATIVE-ERROR with code -2 for a bad argument detected on the Lisp side."
  (error 'native-error :function function :code -2 :message (apply #'format nil fmt args)))

(defmacro ccall (cname &rest args)
  "Call the foreign function of CNAME with ARGS, interrupts deferred (a plan thread that is
evaporated never unwinds out of the middle of a native call); signal NATIVE-ERROR on a
negative result, else return the result.  The shim masks floating point traps itself for the
duration of every call and restores the caller's modes on return."
  (let ((r (gensym "R")) (sym (intern (format nil "%~:@(~a~)" (substitute #\- #\_ cname)))))
    `(let ((,r (sb-sys:without-interrupts (,sym ,@args))))
       (declare (type (signed-byte 32) ,r))
       (if (minusp ,r) (signal-native-error ,cname ,r) ,r))))

(defmacro defcn (cname ret &rest args)
  "Define the raw foreign function %NAME for the shim function CNAME."
  `(cffi:defcfun (,cname ,(intern (format nil "%~:@(~a~)" (substitute #\- #\_ cname))))
       ,ret ,@args))

(defun native-version ()
  "Version of the loaded shim as 10000*major + 100*minor + patch."
  (with-float-traps-masked* (%version)))

;;; ---- argument conversion -------------------------------------------------------------

(deftype dvec () '(simple-array double-float (*)))
(deftype ivec () '(simple-array (signed-byte 32) (*)))

(defun to-dvec (x n function what)
  "X (a sequence of N reals or a DVEC) as a fresh or the same DVEC of length N."
  (cond ((and (typep x 'dvec) (or (null n) (= (length x) n))) x)
        ((and (typep x 'sequence) (or (null n) (= (length x) n))
              (every #'realp x))
         (map 'dvec (lambda (v) (coerce v 'double-float)) x))
        (t (arg-error function "~a is ~s, expected ~:[a sequence of reals~;~:*~d reals~]"
                      what x n))))

(defun pose-vec (pose function &optional (what "pose"))
  "POSE as a DVEC of 7: accepts a DVEC/sequence x y z qx qy qz qw or ((x y z) (qx qy qz qw))."
  (cond ((and (typep pose 'dvec) (= (length pose) 7)) pose)
        ((and (consp pose) (= (length pose) 2) (listp (first pose)) (listp (second pose))
              (= (length (first pose)) 3) (= (length (second pose)) 4))
         (to-dvec (append (first pose) (second pose)) 7 function what))
        (t (to-dvec pose 7 function what))))

(defun to-ivec (x function what)
  "X (a sequence of integers) as an IVEC."
  (cond ((typep x 'ivec) x)
        ((and (typep x 'sequence) (every (lambda (v) (typep v '(signed-byte 32))) x))
         (map 'ivec #'identity x))
        (t (arg-error function "~a is ~s, expected a sequence of integers" what x))))

(defmacro with-vector-pointers (bindings &body body)
  "Bind each (VAR VECTOR) to a pointer to the data of the specialized simple VECTOR (pinned)."
  `(sb-sys:with-pinned-objects ,(mapcar #'second bindings)
     (let ,(mapcar (lambda (b) `(,(first b) (sb-sys:vector-sap ,(second b)))) bindings)
       ,@body)))

(defmacro with-scratch-vector ((var length element-type stack-length) &body body)
  "Run BODY with VAR bound to a fresh simple vector of ELEMENT-TYPE (unevaluated) with room for
at least LENGTH elements: one of STACK-LENGTH (a constant) on the stack when LENGTH fits, else
one of LENGTH on the heap. SBCL puts a DYNAMIC-EXTENT array on the stack only when its size is
a constant and it is under 32 KB. BODY must not keep VAR, nor read past LENGTH."
  (let ((n (gensym "LENGTH")) (fn (gensym "BODY")) (v (gensym "V")))
    `(let ((,n ,length))
       (flet ((,fn (,var)
                (declare (type (simple-array ,element-type (*)) ,var))
                ,@body))
         (declare (dynamic-extent #',fn))
         (if (<= ,n ,stack-length)
             (let ((,v (make-array ,stack-length :element-type ',element-type)))
               (declare (dynamic-extent ,v))
               (,fn ,v))
             (,fn (make-array ,n :element-type ',element-type)))))))

(defun make-dvec (n)
  (make-array n :element-type 'double-float :initial-element 0d0))

(defun real-arg (x function what)
  (if (realp x) (coerce x 'double-float)
      (arg-error function "~a is ~s, expected a real number" what x)))

(defun int-arg (x function what)
  (if (typep x '(signed-byte 32)) x
      (arg-error function "~a is ~s, expected an integer handle or index" what x)))

(defun string-arg (x function what)
  (if (stringp x) x
      (arg-error function "~a is ~s, expected a string" what x)))

(defun path-arg (x function what)
  (cond ((stringp x) x)
        ((pathnamep x) (namestring x))
        (t (arg-error function "~a is ~s, expected a string or pathname" what x))))

;;; ---- search paths ---------------------------------------------------------------------

(defcn "cn_add_package_path" :int (name :string) (dir :string))
(defcn "cn_add_search_dir" :int (dir :string))
(defcn "cn_clear_search_paths" :int)
(defcn "cn_resolve_path" :int (uri :string) (base :string) (out :pointer) (cap :int))

(defun add-package-path (name directory)
  "Resolve package://NAME/... URIs to files under DIRECTORY."
  (ccall "cn_add_package_path" (string-arg name 'add-package-path "package name")
         (path-arg directory 'add-package-path "directory"))
  t)

(defun add-search-dir (directory)
  "Look for package://NAME/... in DIRECTORY/NAME/ (and relative mesh paths in DIRECTORY)."
  (ccall "cn_add_search_dir" (path-arg directory 'add-search-dir "directory"))
  t)

(defun clear-search-paths ()
  "Forget every package path and search directory added from Lisp."
  (ccall "cn_clear_search_paths")
  t)

(defun resolve-path (uri &optional base-directory)
  "The existing file URI (package://, file:// or a path, relative to BASE-DIRECTORY) names."
  (cffi:with-foreign-pointer-as-string ((buf size) 4096)
    (ccall "cn_resolve_path" (path-arg uri 'resolve-path "path")
           (if base-directory (path-arg base-directory 'resolve-path "base directory")
               (cffi:null-pointer))
           buf size)))
