;;;; The shopping assistant: products and a human in the shop, the menus, and the plan that
;;;; walks to the shelves a product should be on, looks for it and points at it.

(in-package :cram-pepper-demo)

(defparameter *shelfoneOffset*
  (cl-transforms:make-transform (cl-transforms:make-3d-vector 0.0 -0.33 0.05)
                                (cl-transforms:make-quaternion 0 0 0 1))
  "From a level link of shelf 1 to where its products stand.")
(defparameter *shelftwoOffset*
  (cl-transforms:make-transform (cl-transforms:make-3d-vector 0.0 -0.25 0.1)
                                (cl-transforms:make-quaternion 0 0 0 1))
  "From a level link of shelf 2 to where its products stand.")
(defparameter *right-offset*
  (cl-transforms:make-transform (cl-transforms:make-3d-vector 0.3 0.0 0.05)
                                (cl-transforms:make-quaternion 0 0 0 1))
  "From a product pose to the look target right of it.")
(defparameter *left-offset*
  (cl-transforms:make-transform (cl-transforms:make-3d-vector -0.3 0.0 0.05)
                                (cl-transforms:make-quaternion 0 0 0 1))
  "From a product pose to the look target left of it.")
(defparameter *robotPoseOffset*
  (cl-transforms:make-transform (cl-transforms:make-3d-vector -0.3 0.0 0.0)
                                (cl-transforms:make-quaternion 0 0 0 1))
  "From the robot's pose to the pose it backs off to for a wider view.")
(defparameter *humanPoseOffset*
  (cl-transforms:make-transform (cl-transforms:make-3d-vector -0.8 0.0 1.0)
                                (cl-transforms:make-quaternion 0 0 1 1))
  "From the robot's pose to where the human follows it.")
(defparameter *look-center* nil "The look target at the product pose.")
(defparameter *look-right* nil "The look target right of the product pose.")
(defparameter *look-left* nil "The look target left of the product pose.")

(defparameter *products*
  '((:my-cereal1 ((4.1 0 1.03) (0 0 1 1)) (1 0 0) :breakfast-cereal)
    (:my-cereal2 ((2 -1.4 1.05) (0 0 1 1)) (1 0 0) :breakfast-cereal)
    (:my-cereal3 ((4.1 0.15 1.73) (0 0 1 1)) (1 0 0) :breakfast-cereal)
    (:my-sachet1 ((4.1 -0.55 1.03) (0 0 1 1)) (0 0.3 0) :somat)
    (:my-sachet2 ((4.1 0.15 1.4) (0 0 1 1)) (0 0.3 0) :somat)
    (:my-sachet3 ((4.1 -0.3 1.73) (0 0 1 1)) (0 0.3 0) :somat)
    (:my-milk1 ((4.1 -0.55 1.4) (0 0 1 1)) (1 0 1) :milk)
    (:my-milk2 ((1.5 -1.4 1.37) (0 0 1 1)) (1 0 1) :milk)
    (:my-bowl1 ((1.5 -1.4 0.52) (0 0 1 1)) (0 0.9 0.9) :bowl)
    (:my-bowl2 ((1.8 -1.4 0.52) (0 0 1 1)) (0 0.9 0.9) :bowl)
    (:my-bar1 ((1.5 -1.4 0.77) (0 0 1 1)) (0.5 0 0.1) :denkmit)
    (:my-bar2 ((1.8 -1.4 0.77) (0 0 1 1)) (0.5 0 0.1) :denkmit))
  "The products of SPAWN-PRODUCTS-ONE: (name pose colour mesh).")

(defun stand-on-support (name)
  "Raise the item NAME so that its bottom rests on the top of the shelf level (or item) below
its origin when it would otherwise stick into it. Returns the metres it was raised."
  (let* ((object (btr:object btr:*current-bullet-world* name))
         (pose (btr:pose object))
         (origin (cl-transforms:origin pose))
         (bottom (cl-transforms:z (btr:aabb object)))
         (support (pp-plans:support-height-below (cl-transforms:x origin) (cl-transforms:y origin)
                                                 (cl-transforms:z origin) :ignore (list name)))
         (lift (if (and support (< bottom support)) (- support bottom) 0d0)))
    (when (plusp lift)
      (setf (btr:pose object)
            (cl-transforms:make-pose (cl-transforms:v+ origin (cl-transforms:make-3d-vector 0 0 lift))
                                     (cl-transforms:orientation pose))))
    lift))

(defun spawn-products-one ()
  "Put the products on the shelves (static, mass 0) and the human into the shop.
The poses of *PRODUCTS* were written for the demo's own product meshes; the household meshes
(the cereal box's origin lies 0.1019 m above its bottom, the milk carton's 0.0877 m) would
stick up to 2.4 cm into the shelf boards there, which hides more than a tenth of a box from
the camera. Each product therefore keeps its x, y and orientation and stands on the board
below it."
  (loop for (name pose color mesh) in *products*
        do (prolog `(and (btr:bullet-world ?world)
                         (assert (btr:object ?world :mesh ,name ,pose
                                             :mass 0 :color ,color :mesh ,mesh))))
           (stand-on-support name))
  (spawn-human))

(defun spawn-human ()
  "Put the (yellow) human behind the robot."
  (prolog '(and (btr:bullet-world ?world)
            (assert (btr:object ?world :mesh :my-human ((-1 0 1) (0 0 1 1))
                                :mass 0.2 :color (1 1 0) :mesh :body :scale 0.3)))))

(defun park-arms ()
  "Put both arms into the park configuration."
  (perform (desig:an action (type positioning-arm)
                     (left-configuration park) (right-configuration park))))

(defun point-front-right ()
  "Point forward with the right arm; the left stays parked."
  (perform (desig:an action (type positioning-arm)
                     (left-configuration park) (right-configuration point-ahead))))

(defun reposition-robot ()
  "Turn the robot at the origin to face the human."
  (prolog `(and (btr:bullet-world ?world)
                (assert (btr:object-pose ?world ,(rob-int:current-robot-name)
                                         ((0 0 0) (0 0 1 0)))))))

(defun reposition-human ()
  "Put the human back at its start."
  (prolog '(and (btr:bullet-world ?world)
            (assert (btr:object-pose ?world :my-human ((-1 0 1) (0 0 1 1)))))))

(defun menu-one ()
  "Greet the user and offer the first menu."
  (princ "Hello my name is Pepper and how may I help you?
		Please use the number corresponding to your request.

		------Select a number-----
		1. Help me find a product.
		2. I just wanted to say hi."))

(defun menu-two ()
  "Offer the products."
  (princ "What do you want?
		Please use the number corresponding to your request.

		------Select a number-----
		1. Cereal.
		2. Milk.
		3. I think I am fine."))

(defun read-choice ()
  "The user's next number from *STANDARD-INPUT*, or NIL at the end of the input."
  (let ((value (let ((*read-eval* nil)) (read *standard-input* nil nil))))
    (cond ((null value) nil)
          ((integerp value) value)
          (t (format t "~&~s is not a number of the menu.~%" value) nil))))

(defun interaction ()
  "The shopping assistant: greet, ask what the user needs (numbers read from
*STANDARD-INPUT*), and lead the user to the product. Returns the product searched for and
whether it was found."
  (urdf-proj:with-simulated-robot (park-arms))
  (reposition-human)
  (reposition-robot)
  (menu-one)
  (let ((?productname nil) (?productposelist nil) (found nil))
    (case (read-choice)
      (1 (menu-two)
       (case (read-choice)
         (1 (setf ?productname 'cereal))
         (2 (setf ?productname 'milk)))
       (when ?productname
         (setf ?productposelist (get-shelf-pose ?productname))
         (format t "~&Alright. Please follow me!~%")
         (setf found (demo-one ?productname ?productposelist))))
      (2 (format t "~&That's nice of you. Thanks!~%")))
    (values ?productname found)))

(defun get-shelf-pose (?product-name)
  "The poses (fixed frame) where ?PRODUCT-NAME should stand on its shelves."
  (let ((shelf-location-list nil))
    (dolist (element (cut:force-ll (prolog `(and (is-on-shelf ,?product-name ?shelf)))))
      (let* ((shelf-name (cut:var-value '?shelf element))
             (shelf-btr-name (cut:var-value '?location
                                            (car (prolog `(and (is-located-at ,shelf-name
                                                                              ?location))))))
             (body (find shelf-btr-name (btr:rigid-bodies (btr:get-environment-object))
                         :key #'btr:name :test #'equalp))
             (shelf-pose-trans (and body (cl-transforms:pose->transform (btr:pose body))))
             (shelf-str (subseq (symbol-name shelf-btr-name) 8 15)))
        (unless body
          (error "GET-SHELF-POSE: the shop has no link ~s for ~s." shelf-btr-name shelf-name))
        (cond ((string-equal shelf-str "shelf_1")
               (push (cl-transforms:transform->pose
                      (cl-transforms:transform* shelf-pose-trans *shelfoneOffset*))
                     shelf-location-list))
              ((string-equal shelf-str "shelf_2")
               (push (cl-transforms:transform->pose
                      (cl-transforms:transform* shelf-pose-trans *shelftwoOffset*))
                     shelf-location-list)))))
    shelf-location-list))
